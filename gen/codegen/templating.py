"""The Jinja2 environment of templates/ and the C literal of a real: what
every template user (render, the backends, the CasADi kernels, the host
module, the FMU) shares, below them all."""
from __future__ import annotations

import functools
import hashlib
import os

import jinja2

from .._version import __version__
from ..core.cache import cache_dir, shipped
from ..core.resources import templates_dir

__all__ = ["template_env", "fmt_real"]


class _BytecodeCache(jinja2.FileSystemBytecodeCache):
    """Jinja's compiled templates in the build cache (parsing and compiling
    them is most of the first render in a process); a cache that cannot be
    written is skipped, never an error."""

    def __init__(self, directory, shipped=None):
        super().__init__(directory)
        self.shipped = shipped          # the same, built at install time (read only)

    def get_cache_key(self, name, filename=None):
        # by the template's name, not its path: the one built at install time
        # was compiled from the checkout (a changed source is still
        # recompiled: the bucket checks its checksum)
        return hashlib.sha1(name.encode("utf-8")).hexdigest()

    def load_bytecode(self, bucket):
        try:
            if self.shipped is not None and not os.path.exists(self._get_cache_filename(bucket)):
                with open(os.path.join(self.shipped, self.pattern % bucket.key), "rb") as f:
                    bucket.load_bytecode(f)
                return
            super().load_bytecode(bucket)
        except (OSError, ValueError, EOFError):
            bucket.reset()

    def dump_bytecode(self, bucket):
        try:
            os.makedirs(self.directory, exist_ok=True)
            super().dump_bytecode(bucket)
        except OSError:
            pass


def _bytecode_cache():
    import sys
    key = hashlib.sha256(f"{__version__}\0{jinja2.__version__}\0{sys.version}\0xml-escaped"
                         "\0by-name".encode())
    name = f"templates_{key.hexdigest()[:16]}"
    pre = shipped(name)                         # built at install time (gen.core.cache)
    return _BytecodeCache(str(cache_dir() / name), None if pre is None else str(pre))


@functools.lru_cache(maxsize=None)
def _env(root):
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(root),
        trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
        undefined=jinja2.StrictUndefined, autoescape=_xml,
        bytecode_cache=_bytecode_cache())


def _xml(name):
    """XML templates (the FMU's) escape every value (& < > " '); C does not."""
    return bool(name) and name.endswith(".xml.j2")


def template_env():
    """The Jinja2 environment of templates/ (SymForce's settings: strict
    undefined, trailing newlines kept; no autoescape but in *.xml.j2)."""
    return _env(str(templates_dir()))

def fmt_real(v, real):
    s = repr(float(v))
    if "e" not in s and "." not in s and "inf" not in s and "nan" not in s:
        s += ".0"
    return s + ("F" if real == "float" else "")
