"""Conditions in a designer's words (used by the elastic diagnosis)."""

from __future__ import annotations

import re


def _words(kind: str | None) -> dict:
    """{condition: (what it asks, what to change, ((phrase, what to change), ...))}: the
    scene's (Scene.condition_words), or with no kind every installed scene's, the first kind
    in order naming a condition giving its words."""
    from .. import plugin

    if kind is not None:
        return plugin.scene_kind(kind).condition_words()
    merged: dict = {}
    for name in plugin.kinds():
        try:
            found = plugin.scene_kind(name).condition_words()
        except plugin.SceneUnavailable:
            continue
        for condition, words in found.items():
            merged.setdefault(condition, words)
    return merged


def hint(name: str, where: str, kind: str | None = None) -> str:
    """What to change, in words, for condition `name` violated at `where` (of a scene of
    `kind`, or of any installed scene)."""
    _, advice, phases = _words(kind).get(name, ("", "", ()))
    for phrase, text in phases:
        if phrase in where:
            return text
    return advice


def normalised_margin(slack: float, scale: float) -> float:
    """The analysis' margin (c - d) / max(c, d) from slack = c - d and scale = c."""
    slack, scale = float(slack), float(scale)
    if scale <= 0.0:
        return slack if scale == 0.0 else -1.0
    return slack / max(scale, scale - slack)


def describe(name: str, where: str, required: float, achieved: float, *,
             equality: bool = False, value: float | None = None, kind: str | None = None) -> str:
    what = _words(kind).get(name, (name.replace("_", " "),))[0]
    advice = hint(name, where, kind)
    place = f" ({where})" if where else ""
    if equality:
        text = f"{what}{place}: cannot be met, best achievable residual {value:.3g}"
    else:
        text = (f"{what}{place}: needs margin {required:.3g}, reaches "
                f"{_reached(required, achieved)} at the least-violation design")
    return f"{text}; try: {advice}" if advice else text


def _reached(required: float, achieved: float) -> str:
    """The margin reached, with its shortfall where 3 digits would print the requirement."""
    if f"{achieved:.3g}" != f"{required:.3g}":
        return f"{achieved:.3g}"
    return f"{required:.3g} less {required - achieved:.2g}"


def _numbered(kind: str | None):
    """The pattern of a numbered place ("flight 3") in a row's `where`: the scene's place nouns
    (Scene.place_nouns), or with no kind every installed scene's; None when there are none."""
    from .. import plugin

    if kind is not None:
        nouns = set(plugin.scene_kind(kind).place_nouns)
    else:
        nouns = set()
        for name in plugin.kinds():
            try:
                nouns.update(plugin.scene_kind(name).place_nouns)
            except plugin.SceneUnavailable:
                continue
    if not nouns:
        return None
    return re.compile(r"\b(" + "|".join(sorted(map(re.escape, nouns))) + r") (\d+)\b")


def summarise(violations, kind: str | None = None) -> list[str]:
    """The elastic diagnosis' violations (most violated first) in words, one line per condition
    and place: a row violated at several numbered places (Scene.place_nouns) is one line that
    names them all, with the worst margin among them (in the words of a scene of `kind`, or of
    any installed one)."""
    numbered = _numbered(kind)
    groups: dict[tuple, list] = {}
    for v in violations:
        pattern = numbered.sub(lambda m: f"{m.group(1)} #", v.where) if numbered else v.where
        key = (v.name, v.text if v.equality else pattern)
        groups.setdefault(key, []).append(v)
    lines = []
    for (name, pattern), members in groups.items():
        if len(members) == 1 or not (numbered and numbered.search(members[0].where)):
            for member in members:
                if member.text not in lines:  # a row held by two keys is one line
                    lines.append(member.text)
            continue
        noun = numbered.search(members[0].where).group(1)
        numbers = sorted({int(numbered.search(v.where).group(2)) for v in members})
        where = pattern.replace(f"{noun} #", f"{noun}s {_spans(numbers)}", 1)
        worst = min(members, key=lambda v: v.achieved - v.required)
        lines.append(describe(name, where, worst.required, worst.achieved, kind=kind))
    return lines


def _spans(numbers: list[int]) -> str:
    """[1, 2, 3, 5] -> '1-3, 5'."""
    spans: list[list[int]] = []
    for n in numbers:
        if spans and n == spans[-1][1] + 1:
            spans[-1][1] = n
        else:
            spans.append([n, n])
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in spans)


def bounds_hint(at_bounds) -> str:
    """The design variables at a bound of the least-violation design, as advice ("" if none)."""
    if not at_bounds:
        return ""
    return (f"at the least-violation design {', '.join(at_bounds)}: widening "
            f"{'that bound' if len(at_bounds) == 1 else 'those bounds'} may help")
