"""Spec files: the typed Spec and the loader that turns TOML into one (or a SpecError)."""

from .loader import load_spec, parse_spec, read_spec_data
from .model import Bounds, Spec

__all__ = ["Bounds", "Spec", "load_spec", "parse_spec", "read_spec_data"]
