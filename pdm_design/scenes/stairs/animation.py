"""The stairs' part of the report page's animation (report/animation.py): the ball's centre and
its spin angle, the integral of the recorded spin rate (counter-clockwise positive), over the
staircase as built; the view is four treads wide."""

from __future__ import annotations

import math

import numpy as np

from ...report.animation import MM, Animation, rounded


def animation(spec, result, timeline) -> Animation:
    """The ball's radius, its spin angle at each frame (rad) and the steps drawn, [back, nose,
    level] (mm)."""
    return Animation(_stairs(spec, result, timeline), SCRIPT)


def _stairs(spec, result, timeline) -> dict:
    r = spec.scene.ball.radius
    t = timeline.times
    omega = timeline.sorted(result.trajectory["omega"])
    spin = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))])
    steps = []
    xs = result.trajectory["x"]
    left, right = min(xs) - 0.5, max(xs) + 0.5
    for s in result.staircase:
        back = s["back"] if math.isfinite(s["back"]) else left
        nose = s["nose"] if math.isfinite(s["nose"]) else right
        if nose < left or back > right:
            continue
        steps.append([round(back * MM, 3), round(nose * MM, 3), round(s["level"] * MM, 3)])
    tread, rise = _stairs_pitch(steps)
    return {"radius": r * MM, "spin": rounded(np.interp(timeline.frames, t, spin), 4),
            "steps": steps,
            "window": max(4.0 * tread, 8.0 * rise, 40 * r * MM, 1.0), "below": 0.0}


def _stairs_pitch(steps):
    """(tread, rise) of the first full step drawn, mm (steps[0] is the launch platform)."""
    if len(steps) >= 3:
        return steps[1][1] - steps[1][0], steps[1][2] - steps[2][2]
    return (steps[0][1] - steps[0][0], 0.0) if steps else (1.0, 0.0)


# the staircase as a polygon, the ball as a circle with a radius that shows its spin
SCRIPT = r"""{
  extent: function (D, xs, ys) {
    D.steps.forEach(function (s) { xs.push(s[0], s[1]); ys.push(s[2]); });
    return 2 * D.radius + 50;
  },
  lift: function (D) { return D.radius; },  // the path of the ball's centre
  build: function (D, el, styled, view) {
    var outline = [], bottom = Math.min.apply(null, D.steps.map(function (s) { return s[2]; }));
    bottom -= D.radius + 100;
    D.steps.forEach(function (s) { outline.push(s[0] + "," + s[2], s[1] + "," + s[2]); });
    outline.push(D.steps[D.steps.length - 1][1] + "," + bottom, D.steps[0][0] + "," + bottom);
    el("polygon", styled({points: outline.join(" "), fill: "#d9d9d9", stroke: "#333"}));
    var ball = el("g", {}), shown = Math.max(D.radius, view.width / 120);
    el("circle", styled({cx: 0, cy: 0, r: shown, fill: "#1f77b4", stroke: "#08306b"}), ball);
    el("line", styled({x1: 0, y1: 0, x2: shown, y2: 0, stroke: "#fff"}), ball);
    return function (i) {
      var deg = D.spin[i] * 180 / Math.PI;
      ball.setAttribute("transform", "translate(" + D.x[i] + "," + (D.y[i] + D.radius) +
                        ") rotate(" + deg + ")");
    };
  }
}"""
