"""The rimless wheel's part of the report page's animation (report/animation.py): the hub at the
recorded (x, y), the spokes turned by the wheel's angle, the ground as the run met it.

The wheel's turn (rad, clockwise: rolling forward) is the stance angle phi unwrapped: phi falls
by the pitch 2 alpha = 2 pi / n at each impact as the next spoke takes over, so phi + 2 alpha m
(m impacts so far) is continuous. The stance spoke at frame i is the one that points from the
hub at the angle -90 deg - (turn_i - 2 alpha m_i) from the x axis (counter-clockwise): its tip is
foothold m_i, `feet[m_i]`, the contact point the simulator recorded."""

from __future__ import annotations

import numpy as np

from ...report.animation import MM, Animation, rounded


def animation(spec, result, timeline) -> Animation:
    """spokes (n), leg (mm), turn at each frame (rad), stance (the foothold index at each
    frame), feet (every foothold, mm) and ground (the surface's polyline, mm)."""
    from .analysis import resolve

    wheel, _, _ = resolve(spec.scene, spec.design_at())
    pitch = 2 * wheel.alpha
    impacts = np.asarray([e.time for e in result.events if e.kind == "impact"], float)
    t = timeline.times
    phi = timeline.sorted(result.trajectory["phi"])
    turn = phi + pitch * _impacts_before(phi, pitch)
    frames = timeline.frames
    stance = np.searchsorted(impacts, frames, side="right")
    feet = [(0.0, 0.0)] + [(s["foot_x"], s["foot_y"]) for s in result.stages]
    leg = wheel.leg * MM
    xs = [f[0] for f in feet]
    return Animation({
        "spokes": wheel.n, "leg": round(leg, 3),
        "turn": rounded(np.interp(frames, t, turn), 5),
        "stance": [int(m) for m in stance],
        "feet": [[round(x * MM, 3), round(y * MM, 3)] for x, y in feet],
        "ground": [[round(x * MM, 3), round(y * MM, 3)] for x, y in ground_outline(spec, result)],
        "window": max(8.0 * wheel.chord * MM, 7.0 * leg), "below": 0.1 * leg,
        "extent_x": [min(xs) * MM - leg, max(xs) * MM + leg]}, SCRIPT)


def _impacts_before(phi, pitch):
    """Impacts before each sample (in time order), counted from the jumps of phi: within a
    stance phi grows (the wheel rolls forward), at an impact it falls by the pitch."""
    drops = np.concatenate([[0], (np.diff(phi) < -0.5 * pitch).astype(int)])
    return np.cumsum(drops)


def ground_outline(spec, result) -> list[tuple[float, float]]:
    """The ground's surface as the run met it, m: the ramp through the recorded footholds, or
    the stairs' treads (each from its back, the recorded foothold less its landing_x, to the
    next tread's back) with vertical risers, tread 0 from landing_offset behind foothold 0."""
    from .analysis import resolve

    feet = [(0.0, 0.0)] + [(s["foot_x"], s["foot_y"]) for s in result.stages]
    _, geometry, _ = resolve(spec.scene, spec.design_at())
    if spec.scene.ground != "stairs":
        (x0, y0), (x1, y1) = feet[0], feet[-1] if len(feet) > 1 else (1.0, 0.0)
        dx, dy = (x1 - x0) / max(len(feet) - 1, 1), (y1 - y0) / max(len(feet) - 1, 1)
        return [(x0 - 2 * dx, y0 - 2 * dy), *feet, (x1 + 2 * dx, y1 + 2 * dy)]
    backs = [-geometry["landing_offset"]]
    backs += [s["foot_x"] - s["landing_x"] for s in result.stages]
    tread = geometry["tread"]
    out = [(backs[0] - 0.5 * tread, 0.0)]
    for k, (back, (_, level)) in enumerate(zip(backs, feet)):
        nose = backs[k + 1] if k + 1 < len(backs) else back + tread
        out += [(back, level), (nose, level)]
    return out


# the ground as a filled polygon, the wheel as spokes about its hub turned at each frame
SCRIPT = r"""{
  extent: function (D, xs, ys) {
    D.ground.forEach(function (p) { xs.push(p[0]); ys.push(p[1]); });
    return D.leg + 50;
  },
  lift: function (D) { return 0; },  // the path of the hub
  build: function (D, el, styled, view) {
    var pts = D.ground.map(function (p) { return p[0] + "," + p[1]; });
    var low = Math.min.apply(null, D.ground.map(function (p) { return p[1]; })) - D.leg;
    pts.push(D.ground[D.ground.length - 1][0] + "," + low, D.ground[0][0] + "," + low);
    el("polygon", styled({points: pts.join(" "), fill: "#d9d9d9", stroke: "#333"}));
    var wheel = el("g", {}), step = 360 / D.spokes;
    for (var j = 0; j < D.spokes; j++) {
      var a = (-90 + j * step) * Math.PI / 180;
      el("line", styled({x1: 0, y1: 0, x2: D.leg * Math.cos(a), y2: D.leg * Math.sin(a),
                         stroke: j ? "#08306b" : "#d62728"}), wheel);
    }
    el("circle", styled({cx: 0, cy: 0, r: Math.max(D.leg / 15, view.width / 150),
                         fill: "#1f77b4", stroke: "#08306b"}), wheel);
    var foot = el("circle", styled({r: Math.max(D.leg / 40, view.width / 300),
                                    fill: "#ff7f0e", stroke: "none"}));
    return function (i) {
      var deg = -D.turn[i] * 180 / Math.PI, f = D.feet[Math.min(D.stance[i], D.feet.length - 1)];
      wheel.setAttribute("transform", "translate(" + D.x[i] + "," + D.y[i] + ") rotate(" +
                         deg + ")");
      foot.setAttribute("cx", f[0]); foot.setAttribute("cy", f[1]);
    };
  }
}"""
