"""Closed-form physics of each scene: pure functions on floats, arrays or CasADi symbols."""
