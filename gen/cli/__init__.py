"""The command line, ``eomgen`` (and ``python -m gen``)."""
from .program import main

__all__ = ["main"]
