"""symkin's version, written into every generated file's header (leaf module)."""

__version__ = "0.1.0"
