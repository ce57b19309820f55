"""Accuracy settings: the simulator's tolerances, the agreement verification demands, and the
preset whose solver settings go with them.

Neutral ground: the simulator, verification and the optimizer's caller (api.py) all read it,
and it imports none of them. It is the one place where a preset name, a mapping of tolerances
(a spec's inline table) or the command line's KEY=VALUE text becomes an Accuracy.
"""

from __future__ import annotations

import math
import reprlib
from collections.abc import Mapping
from dataclasses import dataclass

from .errors import did_you_mean

MIN_RTOL = 2.22e-14  # 100 machine epsilons (to 3 digits, as documented): the integrator's floor
PRESET_NAMES = ("fast", "default", "precise")
TOLERANCE_KEYS = ("rtol", "atol", "event_tol", "agreement")
CARRIES = ("closed", "integrated")
SETTING_KEYS = ("base", *TOLERANCE_KEYS, "carry")  # the keys of a custom accuracy

# What each tolerance must be, in the words of an error message.
_EXPECTED = {
    "rtol": f"a number >= {MIN_RTOL:.3g} (100 machine epsilons) and < 1",
    "atol": "a finite number > 0",
    "event_tol": "a finite number > 0",
    "agreement": "a number > 0 and < 1 (a relative difference)",
    "base": f"one of: {', '.join(PRESET_NAMES)}",
    "carry": f"one of: {', '.join(CARRIES)}",
}
EXPECTED_SETTING = (f"one of: {', '.join(PRESET_NAMES)} (or custom tolerances with keys "
                    f"{', '.join(SETTING_KEYS)})")


class AccuracyError(ValueError):
    """An accuracy setting that cannot be used. key: the offending key ("" for the setting as a
    whole); expected: what it must be; value: what was given; found: what was found, in words,
    when that is more than the value itself (an unknown key); detail: the message without the
    leading "accuracy"."""

    def __init__(self, key: str, expected: str, value, found: str | None = None):
        self.key, self.expected, self.value, self.found = key, expected, value, found
        what = f"expected {expected}, found {found if found is not None else _show(value)}"
        self.detail = f"{key}: {what}" if key else what
        super().__init__(f"accuracy {key}: {what}" if key else f"accuracy: {what}")


def _tolerance(key: str, value) -> float:
    """value as a float if it is a valid `key`, else AccuracyError."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            number = float(value)
        except OverflowError:  # an integer beyond any float
            number = math.inf
        low_ok = number >= MIN_RTOL if key == "rtol" else number > 0.0
        high_ok = number < 1.0 if key in ("rtol", "agreement") else math.isfinite(number)
        if low_ok and high_ok:  # (NaN fails both)
            return number
    raise AccuracyError(key, _EXPECTED[key], value)


@dataclass(frozen=True)
class Accuracy:
    """Tolerances of a simulation run and of its verification.

    rtol, atol: integration tolerances where a scene integrates a phase numerically (a sliding
        carry, a phase with impacts; every other phase is closed form).
    event_tol: absolute tolerance on a located event (s for times, rad for angles, m for a
        contact located by position).
    agreement: relative difference between simulated and closed-form periodic quantities that
        verification accepts (verify.verify_nominal). The presets' values are 10x or more above
        the errors measured by results/bench_accuracy.py (results/accuracy.md).
    base: the preset whose optimizer settings (IPOPT tolerance, starts, random builds verified)
        go with these tolerances; a preset's base is itself.
    carry: the optimizer's carry on real links and pivots (docs/physics.md, section 2.1):
        "closed" (the default) uses the closed form where it applies and integrates only with
        viscous damping, which has none; "integrated" integrates it in the NLP wherever (fourth-
        order steps for a tenth of `agreement`), to compare the two paths (results/bench_links.py).
    """

    name: str
    rtol: float
    atol: float
    event_tol: float
    agreement: float = 1e-7
    base: str = "default"
    carry: str = "closed"

    def __post_init__(self):
        for key in TOLERANCE_KEYS:
            object.__setattr__(self, key, _tolerance(key, getattr(self, key)))
        if self.base not in PRESET_NAMES:
            raise AccuracyError("base", _EXPECTED["base"], self.base)
        if self.carry not in CARRIES:
            raise AccuracyError("carry", _EXPECTED["carry"], self.carry)

    @property
    def is_preset(self) -> bool:
        return ACCURACY_PRESETS.get(self.name) == self

    def settings(self) -> dict:
        """The base preset, every tolerance and the carry, for JSON documents."""
        return ({"base": self.base} | {key: getattr(self, key) for key in TOLERANCE_KEYS}
                | {"carry": self.carry})

    def describe(self) -> str:
        """A preset's name, or the name with every setting, for text reports."""
        if self.is_preset:
            return self.name
        values = ", ".join(f"{key} {getattr(self, key):g}" for key in TOLERANCE_KEYS)
        carry = "" if self.carry == "closed" else f"; carry {self.carry}"
        return f"{self.name}: {values}; base {self.base}{carry}"


ACCURACY_PRESETS = {
    "fast": Accuracy("fast", rtol=1e-6, atol=1e-8, event_tol=1e-7, agreement=1e-4,
                     base="fast"),
    "default": Accuracy("default", rtol=1e-9, atol=1e-11, event_tol=1e-11, agreement=1e-7,
                        base="default"),
    "precise": Accuracy("precise", rtol=1e-12, atol=1e-14, event_tol=1e-14, agreement=1e-9,
                        base="precise"),
}


AccuracySetting = str | Accuracy | Mapping  # what accuracy() takes


def accuracy(setting: AccuracySetting = "default") -> Accuracy:
    """An Accuracy from a preset name, an Accuracy (passed through), or a mapping
    {"base": "default", "rtol": 1e-10, "carry": "integrated", ...}: tolerances left out come
    from the base preset (default "default") and the result is named "custom" (just the base
    preset when no tolerance and no carry is given). AccuracyError (a ValueError) names the
    offending key."""
    if isinstance(setting, Accuracy):
        return setting
    if isinstance(setting, Mapping):
        return _custom(setting)
    if isinstance(setting, str) and setting in ACCURACY_PRESETS:
        return ACCURACY_PRESETS[setting]
    raise AccuracyError("", EXPECTED_SETTING, setting)


def accuracy_from_text(text: str) -> Accuracy:
    """The command line's spelling: a preset name, or KEY=VALUE pairs separated by commas
    ("base=fast,rtol=1e-7")."""
    if "=" not in text:
        return accuracy(text.strip())
    values: dict[str, object] = {}
    for item in text.split(","):
        key, equals, value = (part.strip() for part in item.partition("="))
        if not equals:
            raise AccuracyError("", "KEY=VALUE pairs separated by commas, e.g. rtol=1e-10",
                                item)
        if key in values:
            raise AccuracyError(key, "each key once", text)
        values[key] = _number(key, value) if key in TOLERANCE_KEYS else value
    return accuracy(values)


def _custom(values: Mapping) -> Accuracy:
    for key in values:
        if key not in SETTING_KEYS:
            raise AccuracyError(key, f"a key of accuracy ({', '.join(SETTING_KEYS)})", key,
                                found=f"unknown key {_show(key)}{did_you_mean(key, SETTING_KEYS)}")
    base = values.get("base", "default")
    if not isinstance(base, str) or base not in ACCURACY_PRESETS:
        raise AccuracyError("base", _EXPECTED["base"], base)
    preset = ACCURACY_PRESETS[base]
    if not set(values) & {*TOLERANCE_KEYS, "carry"}:
        return preset
    return Accuracy("custom", base=base, carry=values.get("carry", preset.carry),
                    **{key: values.get(key, getattr(preset, key)) for key in TOLERANCE_KEYS})


def _number(key: str, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise AccuracyError(key, _EXPECTED[key], text) from None


def _show(value) -> str:
    return reprlib.repr(value)  # short, and safe on deeply nested or unprintable values
