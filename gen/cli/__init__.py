"""The command line, ``eomgen`` (and ``python -m gen``)."""
from .commands import main

__all__ = ["main"]
