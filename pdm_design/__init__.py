"""pdm-design: design passive dynamic object manipulation systems."""

__version__ = "0.1.0"
