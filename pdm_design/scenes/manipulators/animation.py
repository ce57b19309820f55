"""The manipulators' part of the report page's animation (report/animation.py): every palm's
angle as key frames, (time, angle) pairs the page interpolates linearly: at rest on its back stop
until it carries the object, the simulator's samples while it carries it, then from its release
(the recorded handover angle) straight to the stop it comes to rest on (the simulator's arrival
event: the empty palm's swing between the two is not recorded, and is drawn as a straight
interpolation of the angle). The view is five pitches wide."""

from __future__ import annotations

import math

import numpy as np

from ...report.animation import MM, Animation


def animation(spec, result) -> Animation:
    """Every palm's pivot and key frames, [time (s), angle (rad)], and the row's sizes (mm)."""
    return Animation(_manipulators(spec, result), SCRIPT)


def _manipulators(spec, result) -> dict:
    from .sim.geometry import build_row

    design = spec.design_at()
    stages = max(len(result.stages), max((e.stage for e in result.events), default=1), 1)
    row = build_row(spec.scene, design, stages, spec.verification.stage_list("offsets"))
    keys = [[[0.0, -row.alpha]] for _ in range(len(row))]
    traj = result.trajectory
    for time, theta, carrier in zip(traj["time"], traj["theta"], traj["manipulator"]):
        k = int(carrier) - 1
        if 0 <= k < len(row) and math.isfinite(theta):
            keys[k].append([time, theta])
    for rec in result.stages:
        k = int(rec["manipulator"]) - 1
        if 0 <= k < len(row) and rec.get("handover_time") is not None:
            keys[k].append([rec["handover_time"], rec["handover_angle"]])
    for e in result.events:
        if e.kind in ("back_stop", "front_stop") and 1 <= e.stage <= len(row):
            keys[e.stage - 1].append([e.time, e.after["theta"]])
    palms = []
    for (px, py), k in zip(row.pivots, keys):
        k.sort(key=lambda p: p[0])
        palms.append({"pivot": [round(px * MM, 3), round(py * MM, 3)],
                      "keys": [[round(a, 5), round(b, 6)] for a, b in _thin(k)]})
    pitch = abs(row.pivots[1][0] - row.pivots[0][0]) if len(row) > 1 else row.palm_width
    return {"window": max(5.0 * pitch, 3.6 * row.link_length) * MM,
            "below": 0.5 * row.link_length * MM,
            "link": row.link_length * MM, "palm_width": row.palm_width * MM,
            "palm_thickness": row.palm_thickness * MM, "hole_spacing": row.palm_width * MM / 2,
            "body_width": row.body_width * MM, "body_height": row.body_height * MM,
            "palms": palms}


def _thin(keys, limit=400):
    """At most `limit` key frames (evenly chosen, first and last kept)."""
    if len(keys) <= limit:
        return keys
    pick = np.unique(np.linspace(0, len(keys) - 1, limit).round().astype(int))
    return [keys[i] for i in pick]


# each palm on its two links, turned to its key frames' angle; the object as a rectangle
SCRIPT = r"""{
  extent: function (D, xs, ys) {
    D.palms.forEach(function (p) {
      xs.push(p.pivot[0] - D.link - D.palm_width / 2, p.pivot[0] + D.link + D.palm_width / 2);
      ys.push(p.pivot[1] - D.link, p.pivot[1] + D.link);
    });
    return D.body_height + 50;
  },
  lift: function (D) { return 0; },
  build: function (D, el, styled, view) {
    var h = D.hole_spacing / 2;
    var parts = D.palms.map(function (p) {
      el("circle", {cx: p.pivot[0], cy: p.pivot[1], r: D.link / 60, fill: "#000"});
      return {links: [el("line", styled({stroke: "#555"})), el("line", styled({stroke: "#555"}))],
              palm: el("rect", styled({width: D.palm_width, height: D.palm_thickness,
                                       fill: "#bdbdbd", stroke: "#000"}))};
    });
    var body = el("rect", styled({width: D.body_width, height: D.body_height, fill: "#2ca02c",
                                  "fill-opacity": 0.75, stroke: "#005a00"}));
    var angle = function (keys, t) {
      if (t <= keys[0][0]) return keys[0][1];
      for (var j = 1; j < keys.length; j++) {
        if (t <= keys[j][0]) {
          var a = keys[j - 1], b = keys[j], f = b[0] > a[0] ? (t - a[0]) / (b[0] - a[0]) : 1;
          return a[1] + f * (b[1] - a[1]);
        }
      }
      return keys[keys.length - 1][1];
    };
    return function (i) {
      var t = D.t[i];
      D.palms.forEach(function (p, k) {
        var th = angle(p.keys, t), px = p.pivot[0], py = p.pivot[1];
        var cx = px + D.link * Math.sin(th), cy = py + D.link * Math.cos(th);
        [-h, h].forEach(function (dx, m) {
          var line = parts[k].links[m];
          line.setAttribute("x1", px + dx); line.setAttribute("y1", py - D.palm_thickness);
          line.setAttribute("x2", cx + dx); line.setAttribute("y2", cy - D.palm_thickness);
        });
        parts[k].palm.setAttribute("x", cx - D.palm_width / 2);
        parts[k].palm.setAttribute("y", cy - D.palm_thickness);
      });
      body.setAttribute("x", D.x[i] - D.body_width / 2);
      body.setAttribute("y", D.y[i]);
    };
  }
}"""
