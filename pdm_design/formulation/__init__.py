"""Formulation layer: a spec -> one CasADi NLP (built once, solved many times) + inverse map."""

from .build import formulate

__all__ = ["formulate"]
