"""The version of eomgen (one place: the package, the generated banners and the cache keys read it)."""
__version__ = "0.1.0"
