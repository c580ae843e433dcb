"""Where the live view listens, and the address printed for a browser.

The view serves on this machine only (``127.0.0.1``) unless asked otherwise. Serving on every
interface lets anyone who can reach the machine open the page and drive it, so it must be asked
for in one of two explicit spellings, ``0.0.0.0`` (every IPv4 interface) or ``::`` (every
interface, IPv6 and on most systems IPv4 too), and it is said with a warning. Every other host
that means "every interface" is refused with a ParameterError naming those two: an empty host
(``--host "$VAR"`` with the variable unset), ``*``, ``0``, ``::0``, ``[::]``, ``0:0::0``, or a
name that resolves to an unspecified address. The printed URL is one a browser opens: the
loopback address for a wildcard, an IPv6 address in brackets (its zone as ``%25``), a name as
given.
"""

from __future__ import annotations

import ipaddress
import socket
from dataclasses import dataclass

from symkin.errors import ParameterError

__all__ = ["EVERY_INTERFACE", "Address", "serve_address"]

#: The two explicit spellings of "serve on every interface" (IPv4, IPv6).
EVERY_INTERFACE = ("0.0.0.0", "::")


@dataclass(frozen=True)
class Address:
    """A host to serve on: ``host``, what the server binds; ``browser``, the host part of a URL a
    browser opens (brackets around IPv6); ``public``, whether it is every interface."""

    host: str
    browser: str
    public: bool

    def url(self, port: int) -> str:
        """``http://browser:port``."""
        return f"http://{self.browser}:{int(port)}"

    def warning(self, port: int) -> str:
        """The line that says a public server is public (empty for a private one)."""
        if not self.public:
            return ""
        return (
            f"serving on every interface ({self.host} port {int(port)}): anyone who can reach this "
            "machine can open the view and drive it; --host 127.0.0.1 serves this machine only"
        )


def serve_address(host: object) -> Address:
    """The :class:`Address` of ``host`` (see the module docstring); ParameterError for a host that
    is not text, empty, or a wildcard spelled otherwise than ``0.0.0.0`` or ``::``; OSError when
    it does not resolve."""
    if not isinstance(host, str):
        raise ParameterError(f"host must be text such as '127.0.0.1', got {host!r}")
    if host in EVERY_INTERFACE:
        return Address(host, "127.0.0.1" if host == "0.0.0.0" else "[::1]", True)
    text = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    if not text.strip():
        raise ParameterError(
            f"host {host!r} is empty (an unset variable?), which would serve on every interface: give "
            "127.0.0.1 for this machine only, or 0.0.0.0 (or ::) to serve every interface on purpose"
        )
    if text != text.strip() or any(c in text for c in "*/?#@") or _wildcard(text):
        raise ParameterError(
            f"host {host!r} is not a host to serve on, or means every interface: give 127.0.0.1 for "
            "this machine only, or exactly 0.0.0.0 (or ::) to serve every interface on purpose"
        )
    return Address(text, _browser(text), False)


def _wildcard(text: str) -> bool:
    """Whether ``text`` resolves to an unspecified address (what binding to every interface means);
    OSError when it does not resolve at all."""
    try:
        infos = socket.getaddrinfo(text, None, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise OSError(f"cannot serve on {text}: {reason}") from None
    for info in infos:
        ip = ipaddress.ip_address(str(info[4][0]).split("%")[0])
        mapped = getattr(ip, "ipv4_mapped", None)
        if ip.is_unspecified or (mapped is not None and mapped.is_unspecified):
            return True
    return False


def _browser(text: str) -> str:
    """The host part of a URL for ``text``: an IPv6 literal in brackets (zone ``%`` as ``%25``)."""
    address, _, zone = text.partition("%")
    try:
        ip = ipaddress.ip_address(address)
    except ValueError:
        return text  # a name
    if ip.version == 6:
        return f"[{ip.compressed}{'%25' + zone if zone else ''}]"
    return ip.compressed
