"""Compile C sources into a cached shared library, safely under concurrency.

A cache entry is a folder ``<cache>/<name>-<key>/`` holding the sources, ``lib<name>.so``,
``lib<name>.so.build`` (the hash of the sources and flags, so a warm cache works without a
compiler) and ``lib<name>.so.sha256`` (the library's checksum, written last). ``key`` is a sha256 of the
sources, the flags and the compiler's identity (resolved path, size, mtime; the host name too
when the flags contain ``-march=native``). An entry is built in a temporary folder inside the
cache and moved into place with one ``rename``, so readers never see a half-written entry and the
first of several concurrent builders wins (the others use its entry). An entry whose library no
longer matches its checksum (truncated, overwritten) is moved aside and rebuilt.

Environment: ``SYMKIN_CACHE`` (cache folder, default ``~/.cache/symkin``), ``CC`` (compiler
command, default ``cc``, then ``gcc``, then ``clang``), ``SYMKIN_CFLAGS`` (replaces the
optimisation flags ``-O2 -march=native``).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import hashlib
import importlib.machinery
import importlib.util
import os
import re
import shlex
from collections.abc import Mapping, Sequence
from functools import lru_cache
from pathlib import Path
from types import ModuleType

from symkin.core.cache import cache_dir
from symkin.errors import CompileError

__all__ = [
    "compile_library",
    "cached_library",
    "load_library",
    "load_extension",
    "find_compiler",
    "check_cflags",
    "DEFAULT_OPT_FLAGS",
    "BASE_FLAGS",
]

DEFAULT_OPT_FLAGS: tuple[str, ...] = ("-O2", "-march=native")  # -O3: same speed, 1 s slower to build
# -ffp-contract=off: no fused multiply-add, so results round like NumPy's (FMA changes them at 1e-16).
# -fno-tree-slp-vectorize: GCC 12's straight-line vectoriser emits fused vfmsubadd even with
# -ffp-contract=off (1-ulp differences); measured: no loss of speed on the generated kinematics.
BASE_FLAGS: tuple[str, ...] = (
    "-std=c11",
    "-fPIC",
    "-shared",
    "-ffp-contract=off",
    "-fno-tree-slp-vectorize",
    "-fno-math-errno",
)
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_FILE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]*\.(c|h)$")
_NO_COMPILER_HINT = "The NumPy backend works without a C compiler (backend='numpy')."


def find_compiler() -> list[str]:
    """The C compiler command as an argument list: ``$CC`` or the first of cc, gcc, clang on PATH.

    Raises CompileError when there is none.
    """
    return list(_find_compiler(os.environ.get("CC", ""), os.environ.get("PATH", "")))


@lru_cache(maxsize=16)
def _find_compiler(cc_env: str, path_env: str) -> tuple[str, ...]:
    import shutil

    if cc_env.strip():
        argv = shlex.split(cc_env)
        exe = shutil.which(argv[0], path=path_env)
        if exe is None:
            raise CompileError(
                f"the C compiler CC={cc_env!r} was not found. Install gcc or clang, or point CC at one. "
                + _NO_COMPILER_HINT
            )
        return (exe, *argv[1:])
    for name in ("cc", "gcc", "clang"):
        exe = shutil.which(name, path=path_env)
        if exe:
            return (exe,)
    raise CompileError(
        "no C compiler found (looked for cc, gcc, clang on PATH; set CC). " + _NO_COMPILER_HINT
    )


def _compiler_identity(argv: Sequence[str]) -> str:
    real = os.path.realpath(argv[0])
    try:
        st = os.stat(real)
    except OSError as exc:
        raise CompileError(f"cannot use the C compiler {argv[0]}: {exc}. " + _NO_COMPILER_HINT) from None
    return f"{real}:{st.st_size}:{st.st_mtime_ns}:{' '.join(argv[1:])}"


def _flags(extra_cflags: Sequence[str]) -> list[str]:
    env = os.environ.get("SYMKIN_CFLAGS")
    try:
        opt = shlex.split(env) if env is not None else list(DEFAULT_OPT_FLAGS)
    except ValueError as exc:
        raise CompileError(f"SYMKIN_CFLAGS={env!r} cannot be parsed as shell words: {exc}") from None
    return [*BASE_FLAGS, *opt, *extra_cflags]


def _cflags_hint() -> str:
    env = os.environ.get("SYMKIN_CFLAGS")
    return (
        "" if env is None else f" with SYMKIN_CFLAGS={env!r} (unset it to use {' '.join(DEFAULT_OPT_FLAGS)})"
    )


def check_cflags() -> None:
    """Raise CompileError naming ``SYMKIN_CFLAGS`` when it is set and cannot be parsed or the C
    compiler rejects it (one tiny test compile per process and setting). Without a compiler
    nothing is checked: a warm cache may still serve."""
    env = os.environ.get("SYMKIN_CFLAGS")
    if env is None:
        return
    flags = _flags(())
    try:
        compiler = find_compiler()
    except CompileError:
        return
    error = _probe(tuple(compiler), tuple(flags))
    if error:
        raise CompileError(f"the C compiler rejects SYMKIN_CFLAGS={env!r}: {error}")


@lru_cache(maxsize=8)
def _probe(compiler: tuple[str, ...], flags: tuple[str, ...]) -> str:
    """'' when ``compiler`` builds a tiny shared library with ``flags`` (or the probe cannot be
    written, or the compiler runs out of space: a full disk says nothing of the flags), else its
    first error line."""
    try:
        return _probe_in(compiler, flags)
    except OSError:
        return ""


def _probe_in(compiler: tuple[str, ...], flags: tuple[str, ...]) -> str:
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory(prefix="symkin-cflags-") as tmp:
        (Path(tmp) / "probe.c").write_text("double symkin_probe(double x) { return x + 1.0; }\n")
        try:
            proc = subprocess.run(
                [*compiler, *flags, "-o", "probe.so", "probe.c"],
                cwd=tmp,
                capture_output=True,
                text=True,
                timeout=60,
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            return str(exc)
        if proc.returncode == 0 or any(reason in proc.stderr for reason in _UNWRITABLE):
            return ""
        lines = [ln for ln in (proc.stderr or proc.stdout).splitlines() if "error" in ln.lower()]
        return (lines or (proc.stderr or proc.stdout or f"exit {proc.returncode}").splitlines() or [""])[
            0
        ].strip()


def _check_inputs(sources: Mapping[str, str], name: str) -> None:
    if not isinstance(name, str) or not _NAME.match(name):
        raise CompileError(f"library name {name!r} must be an identifier (letters, digits, underscores)")
    if not sources:
        raise CompileError("no sources to compile")
    for fname, text in sources.items():
        if not isinstance(fname, str) or not _FILE.match(fname) or ".." in fname:
            raise CompileError(f"source file name {fname!r} must be a plain name ending in .c or .h")
        if not isinstance(text, str):
            raise CompileError(f"source {fname!r} must be text, not {type(text).__name__}")
    if not any(f.endswith(".c") for f in sources):
        raise CompileError(f"no .c file among the sources {sorted(sources)}")


def _build_key(sources: Mapping[str, str], flags: Sequence[str]) -> str:
    """Hash of what a build depends on apart from the compiler: sources, flags (and the host when
    the flags tune for it). Stored in each entry, so a warm cache works without a compiler."""
    import platform

    h = hashlib.sha256()
    for fname in sorted(sources):
        data = sources[fname].encode()
        h.update(f"{fname}\0{len(data)}\0".encode())
        h.update(data)
    h.update("\0".join(flags).encode())
    if any("native" in f for f in flags):
        h.update(f"\0{platform.node()}:{platform.machine()}".encode())
    return h.hexdigest()


def _key(sources: Mapping[str, str], flags: Sequence[str], compiler: Sequence[str]) -> str:
    text = _build_key(sources, flags) + "\0" + _compiler_identity(compiler)
    return hashlib.sha256(text.encode()).hexdigest()


def _sha256_file(path: Path) -> str:
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def _valid(entry: Path, lib: str, build_key: str) -> bool:
    """True when the entry was built from ``build_key`` (its sources and flags) and its library
    matches the checksum written after it."""
    try:
        if (entry / (lib + ".build")).read_text().strip() != build_key:
            return False
        expected = (entry / (lib + ".sha256")).read_text().strip()
        return bool(expected) and _sha256_file(entry / lib) == expected
    except OSError:
        return False


def _without_compiler(root: Path, name: str, lib: str, build_key: str) -> Path | None:
    """The newest intact cache entry of ``name`` built from the same sources and flags, by any
    compiler (used when no compiler is found), or None."""
    found = []
    try:
        for entry in root.glob(f"{name}-*"):
            if _valid(entry, lib, build_key):
                found.append((entry.stat().st_mtime_ns, entry))
    except OSError:
        return None
    return max(found)[1] / lib if found else None


def _build(
    tmp: Path, sources: Mapping[str, str], lib: str, flags: Sequence[str], compiler: Sequence[str]
) -> None:
    import subprocess

    for fname, text in sources.items():
        (tmp / fname).write_text(text)
    cfiles = sorted(f for f in sources if f.endswith(".c"))
    cmd = [*compiler, *flags, "-o", lib, *cfiles, "-lm"]
    try:
        proc = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True, timeout=600)
    except FileNotFoundError:
        raise CompileError(f"the C compiler {compiler[0]} could not be run. " + _NO_COMPILER_HINT) from None
    except subprocess.TimeoutExpired:
        raise CompileError(f"compiling {', '.join(cfiles)} took more than 600 s") from None
    if proc.returncode != 0 or not (tmp / lib).is_file():
        _raise_if_unwritable(proc.stderr + proc.stdout, tmp)
        lines = (proc.stderr or proc.stdout or "").strip().splitlines()
        shown = "\n".join(lines[:25]) + (f"\n... ({len(lines) - 25} more lines)" if len(lines) > 25 else "")
        raise CompileError(
            f"the C compiler failed (exit {proc.returncode}) on {', '.join(cfiles)}{_cflags_hint()}:\n"
            f"  {shlex.join(cmd)}\n{shown}"
        )
    (tmp / (lib + ".build")).write_text(_build_key(sources, flags) + "\n")
    checksum = tmp / (lib + ".sha256")
    checksum.write_text(_sha256_file(tmp / lib) + "\n")


# what the compiler prints when a disk filled up under it (the strerror texts of Python's C library)
_UNWRITABLE = tuple(os.strerror(e) for e in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG))


def _raise_if_unwritable(output: str, folder: Path) -> None:
    """OSError when the compiler's ``output`` says a disk is full (its output in ``folder``, or its
    temporary files): the disk's fault, not the sources'."""
    for reason in _UNWRITABLE:
        if reason in output:
            raise OSError(f"the C compiler could not write into {folder}: {reason}")


def compile_library(sources: Mapping[str, str], name: str, extra_cflags: Sequence[str] = ()) -> Path:
    """Compile ``sources`` (file name -> text, ``.c`` and ``.h``) into a cached shared library.

    Returns the path of ``lib<name>.so`` inside its cache entry. A cached, intact entry is
    returned without compiling (about 0.1 ms); without a C compiler, an entry built from the same
    sources and flags by any compiler is used. When the cache cannot be written (full, over quota,
    read-only, not a folder), the library is built in a temporary folder (removed at exit): it
    only costs speed. Raises CompileError when no compiler is found (and nothing is cached),
    compilation fails (with the first lines of the compiler's output), or neither the cache nor a
    temporary folder can be written (naming both).
    """
    import shutil
    import tempfile

    found, entry, flags, compiler = _lookup(sources, name, extra_cflags)
    if found is not None:
        return found
    if entry is None or compiler is None:  # no compiler and nothing cached
        find_compiler()  # raises CompileError with the hint
        raise CompileError("no C compiler found")
    root, lib = entry.parent, f"lib{name}.so"
    build_key = _build_key(sources, flags)
    try:
        root.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".tmp-{name}-", dir=root))
    except OSError:
        return _build_uncached(sources, name, lib, flags, compiler)
    try:
        try:
            _build(tmp, sources, lib, flags, compiler)
        except OSError:  # the cache filled up (or became unwritable) while building
            return _build_uncached(sources, name, lib, flags, compiler)
        for _ in range(5):
            try:
                os.rename(tmp, entry)  # atomic; fails when another process placed the entry first
                return entry / lib
            except OSError:
                if _valid(entry, lib, build_key):
                    return entry / lib
                if not _discard(entry, root):  # corrupt entry that cannot be moved aside: keep ours
                    _keep_until_exit(tmp)
                    return tmp / lib
        raise CompileError(f"could not place the cache entry {entry} (another process keeps replacing it)")
    finally:
        if tmp.exists() and tmp not in _UNCACHED:
            shutil.rmtree(tmp, ignore_errors=True)


def cached_library(sources: Mapping[str, str], name: str, extra_cflags: Sequence[str] = ()) -> Path | None:
    """The library :func:`compile_library` would return without compiling (a cached, intact
    entry; without a C compiler, one built by any compiler), or None when it would compile."""
    return _lookup(sources, name, extra_cflags)[0]


def _lookup(
    sources: Mapping[str, str], name: str, extra_cflags: Sequence[str]
) -> tuple[Path | None, Path | None, list[str], list[str] | None]:
    """(the cached library or None, its entry folder, the flags, the compiler: None when there is
    none, and then no entry either)."""
    _check_inputs(sources, name)
    flags = _flags(extra_cflags)
    root = cache_dir()
    lib = f"lib{name}.so"
    build_key = _build_key(sources, flags)
    try:
        compiler = find_compiler()
    except CompileError:
        return _without_compiler(root, name, lib, build_key), None, flags, None
    entry = root / f"{name}-{_key(sources, flags, compiler)[:24]}"
    return (entry / lib if _valid(entry, lib, build_key) else None), entry, flags, compiler


_UNCACHED: list[Path] = []


def _build_uncached(
    sources: Mapping[str, str], name: str, lib: str, flags: Sequence[str], compiler: Sequence[str]
) -> Path:
    """Build in a private temporary folder (the cache is not writable); removed at exit."""
    import shutil
    import tempfile

    tmp = None
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f"symkin-{name}-"))
        _build(tmp, sources, lib, flags, compiler)
    except OSError as exc:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
        raise CompileError(
            f"cannot write to the symkin cache {cache_dir()} (SYMKIN_CACHE) nor the temporary folder "
            f"{tempfile.gettempdir()} (TMPDIR): {exc.strerror or exc}; free some space or point "
            "SYMKIN_CACHE at a writable folder"
        ) from None
    _keep_until_exit(tmp)
    return tmp / lib


def _keep_until_exit(folder: Path) -> None:
    """Remove ``folder`` (a build outside the cache) when the interpreter exits."""
    import atexit

    if not _UNCACHED:
        atexit.register(_remove_uncached)
    _UNCACHED.append(folder)


def _remove_uncached() -> None:
    import shutil

    for path in _UNCACHED:
        shutil.rmtree(path, ignore_errors=True)


def _discard(entry: Path, root: Path) -> bool:
    """Move a bad entry out of the way atomically (a no-op when someone else already did); False
    when the cache cannot take the folder to move it into (full, read-only)."""
    import shutil
    import tempfile

    try:
        trash = Path(tempfile.mkdtemp(prefix=".trash-", dir=root))
    except OSError:
        return False
    with contextlib.suppress(OSError):
        os.rename(entry, trash / "entry")
    shutil.rmtree(trash, ignore_errors=True)
    return True


_LOADED: dict[tuple[str, int, int], ctypes.CDLL] = {}


def load_library(path: str | os.PathLike[str]) -> ctypes.CDLL:
    """``ctypes.CDLL`` of a shared library, memoised per file (path, inode, mtime)."""
    p = os.fspath(path)
    try:
        st = os.stat(p)
    except OSError as exc:
        raise CompileError(f"cannot load {p}: {exc}") from None
    k = (p, st.st_ino, st.st_mtime_ns)
    lib = _LOADED.get(k)
    if lib is None:
        try:
            lib = ctypes.CDLL(p)
        except OSError as exc:
            raise CompileError(f"cannot load the compiled library {p}: {exc}") from None
        _LOADED[k] = lib
    return lib


def load_extension(name: str, path: Path) -> ModuleType:
    """Import the extension module ``name`` from the shared library at ``path``."""
    import sys

    if name in sys.modules:
        return sys.modules[name]
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, str(path), loader=loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[name] = module
    return module
