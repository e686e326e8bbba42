"""The package version (one place, imported by the package and by the CAD cache key)."""

__version__ = "0.1.0"
