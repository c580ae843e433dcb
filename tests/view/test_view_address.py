"""Where the live view listens (symkin.view.address, issue 36 item 2): an empty host (``--host
"$VAR"`` with the variable unset) served on every interface and printed ``http://:PORT``; now
every interface is served only when asked for as exactly 0.0.0.0 or ::, and the printed URL is
one a browser opens."""

from __future__ import annotations

import socket

import pytest

import symkin
from symkin.view.address import EVERY_INTERFACE, serve_address

# every spelling of "every interface" other than the two explicit ones, and empty hosts
WILDCARDS = ["", " ", "\t", "*", "0", "0.0", "0x0", "000.000.000.000", "::0", "0:0:0:0:0:0:0:0", "0::",
             "[::]", "[0::0]", "::ffff:0.0.0.0", " 0.0.0.0", "0.0.0.0 ", ":: "]  # fmt: skip


@pytest.mark.parametrize("host", WILDCARDS)
def test_empty_and_wildcard_hosts_are_refused(host):
    with pytest.raises(symkin.ParameterError, match="127.0.0.1") as info:
        serve_address(host)
    assert "0.0.0.0" in str(info.value)  # names the explicit form


@pytest.mark.parametrize("host", [None, 0, b"127.0.0.1", ["127.0.0.1"]])
def test_a_host_that_is_not_text_is_refused(host):
    with pytest.raises(symkin.ParameterError, match="text"):
        serve_address(host)


def test_a_name_that_resolves_to_the_wildcard_is_refused(monkeypatch):
    """A name the resolver maps to 0.0.0.0 (an /etc/hosts blocking line) is every interface too."""
    real = socket.getaddrinfo

    def resolve(host, *args, **kwargs):
        if host == "blocked.example":
            return [(socket.AF_INET, socket.SOCK_STREAM, 6, "", ("0.0.0.0", 0))]
        return real(host, *args, **kwargs)

    monkeypatch.setattr(socket, "getaddrinfo", resolve)
    with pytest.raises(symkin.ParameterError, match="every interface"):
        serve_address("blocked.example")


@pytest.mark.parametrize(
    "host, bound, browser",
    [
        ("0.0.0.0", "0.0.0.0", "127.0.0.1"),
        ("::", "::", "[::1]"),
    ],
)
def test_every_interface_only_when_spelled_out_and_then_with_a_warning(host, bound, browser):
    address = serve_address(host)
    assert address.public and address.host == bound and address.url(8080) == f"http://{browser}:8080"
    assert "every interface" in address.warning(8080) and host in address.warning(8080)
    assert host in EVERY_INTERFACE


@pytest.mark.parametrize(
    "host, bound, url",
    [
        ("127.0.0.1", "127.0.0.1", "http://127.0.0.1:80"),
        ("localhost", "localhost", "http://localhost:80"),
        ("::1", "::1", "http://[::1]:80"),  # was http://::1:80, which no browser opens
        ("[::1]", "::1", "http://[::1]:80"),
        ("0:0:0:0:0:0:0:1", "0:0:0:0:0:0:0:1", "http://[::1]:80"),
    ],
)
def test_the_printed_url_is_one_a_browser_opens(host, bound, url):
    try:
        address = serve_address(host)
    except OSError:
        pytest.skip(f"{host} does not resolve here")
    assert not address.public and address.host == bound and address.url(80) == url
    assert address.warning(80) == ""


def test_an_ipv6_zone_is_percent_encoded_in_the_url():
    from symkin.view.address import _browser

    assert _browser("fe80::1%eth0") == "[fe80::1%25eth0]"


def test_a_host_that_does_not_resolve_is_an_oserror_naming_it():
    with pytest.raises(OSError, match="no-such-host.invalid"):
        serve_address("no-such-host.invalid")
