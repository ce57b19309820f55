"""The compass gait's part of the report page's animation (report/animation.py): the walker (the
hip, the stance leg thick, the swing leg) walking down the ground. The page's object is the hip
(the trajectory's x, y); the stance foot stays where it landed for its whole step and swaps to
the swing foot's place at each heel strike."""

from __future__ import annotations

import numpy as np

from ...report.animation import MM, Animation, rounded


def animation(spec, result, timeline) -> Animation:
    """The leg length, the stance and swing feet at each frame ([x, y], mm) and the ground drawn
    (a polyline, mm)."""
    l = spec.design_at().walker(spec.scene).leg_length
    return Animation(walker_frames(result, timeline, l), SCRIPT)


def walker_frames(result, timeline, leg_length: float) -> dict:
    traj = result.trajectory
    foot_x, foot_y = (timeline.sorted(traj[k]) for k in ("foot_x", "foot_y"))
    swing_x = timeline.sorted(traj["x"]) - leg_length * np.sin(timeline.sorted(traj["swing"]))
    swing_y = timeline.sorted(traj["y"]) - leg_length * np.cos(timeline.sorted(traj["swing"]))
    at, after, share = _within_step(timeline, foot_x, foot_y)
    swing = [swing_x[at] + share * (swing_x[after] - swing_x[at]),
             swing_y[at] + share * (swing_y[after] - swing_y[at])]
    feet = [(0.0, 0.0)] + [(r["foot_x"], r["foot_y"]) for r in result.stages]
    return {"leg": leg_length * MM,
            "foot": _points(foot_x[at], foot_y[at]), "swing": _points(*swing),
            "ground": _ground(feet, leg_length),
            "window": 4.0 * leg_length * MM, "below": 0.4 * leg_length * MM}


def _points(xs, ys) -> list[list[float]]:
    """[[x, y], ...] in mm, rounded to 0.01 mm."""
    return [[round(float(x) * MM, 2), round(float(y) * MM, 2)] for x, y in zip(xs, ys)]


def _within_step(timeline, foot_x, foot_y):
    """For each frame: the sample at or before it, the next sample of the same step (itself at
    the step's last sample) and the frame's share of the way between them; a frame at a heel
    strike shows the step that begins there."""
    times, n = timeline.times, len(timeline.times)
    at = np.clip(np.searchsorted(times, timeline.frames, side="right") - 1, 0, n - 1)
    after = np.minimum(at + 1, n - 1)
    same = (foot_x[after] == foot_x[at]) & (foot_y[after] == foot_y[at]) & (
        times[after] > times[at])
    after = np.where(same, after, at)
    span = np.where(same, times[after] - times[at], 1.0)
    share = np.where(same, (timeline.frames - times[at]) / span, 0.0)
    return at, after, share


def _ground(feet, leg_length) -> list[list[float]]:
    """The ground through the stance feet (m), half a leg beyond the first and the last, mm."""
    pts = np.asarray(feet, dtype=float)
    if len(pts) > 1:
        head = pts[0] - 0.5 * leg_length * _unit(pts[1] - pts[0])
        tail = pts[-1] + 0.5 * leg_length * _unit(pts[-1] - pts[-2])
    else:
        head, tail = pts[0] - [leg_length, 0.0], pts[0] + [leg_length, 0.0]
    return [rounded(p * MM, 2) for p in (head, *pts, tail)]


def _unit(v):
    return v / (np.hypot(*v) or 1.0)


# the ground as a filled polyline; the legs as lines from the hip, the hip as a disc
SCRIPT = r"""{
  extent: function (D, xs, ys) {
    D.ground.forEach(function (p) { xs.push(p[0]); ys.push(p[1]); });
    return 0.3 * D.leg;
  },
  lift: function (D) { return 0; },  // the path drawn is the hip's
  build: function (D, el, styled, view) {
    var g = D.ground, bottom = Math.min.apply(null, g.map(function (p) { return p[1]; }));
    var outline = g.map(function (p) { return p[0] + "," + p[1]; });
    bottom -= D.leg;
    outline.push(g[g.length - 1][0] + "," + bottom, g[0][0] + "," + bottom);
    el("polygon", styled({points: outline.join(" "), fill: "#d9d9d9", stroke: "#333"}));
    var swing = el("line", styled({stroke: "#ff7f0e", "stroke-width": 3}));
    var stance = el("line", styled({stroke: "#1f77b4", "stroke-width": 4}));
    var hip = el("circle", styled({r: Math.max(D.leg / 14, view.width / 150),
                                   fill: "#d62728", stroke: "#67000d"}));
    return function (i) {
      var hx = D.x[i], hy = D.y[i];
      stance.setAttribute("x1", D.foot[i][0]); stance.setAttribute("y1", D.foot[i][1]);
      stance.setAttribute("x2", hx); stance.setAttribute("y2", hy);
      swing.setAttribute("x1", D.swing[i][0]); swing.setAttribute("y1", D.swing[i][1]);
      swing.setAttribute("x2", hx); swing.setAttribute("y2", hy);
      hip.setAttribute("cx", hx); hip.setAttribute("cy", hy);
    };
  }
}"""
