"""The animated run of a report page: the simulator's recorded trajectory as plain data for the
page's script, and the SVG element and script that play it.

Frames are uniform in time (FRAME_RATE a second of simulated time, at most MAX_FRAMES: longer
runs are played with a coarser step), the object's place interpolated between the simulator's
samples. Manipulators: every palm's angle as key frames, (time, angle) pairs the page
interpolates linearly: at rest on its back stop until it carries the object, the simulator's
samples while it carries it, then from its release (the recorded handover angle) straight to the
stop it comes to rest on (the simulator's arrival event: the empty palm's swing between the two
is not recorded, and is drawn as a straight interpolation of the angle). Stairs: the ball's
centre and its spin angle, the integral of the recorded spin rate (counter-clockwise positive).

Coordinates are millimetres, y up; the SVG flips y. A device longer than the page's window
(five pitches, four treads) is shown through a window that follows the object.
"""

from __future__ import annotations

import json
import math

import numpy as np

FRAME_RATE = 30.0     # frames a second of simulated time (played at real time)
MAX_FRAMES = 1500
ELEMENT_ID = "pdm-animation"
MM = 1e3


def animation_data(spec, result) -> dict:
    """Plain data for the page's script: frame times and the object's place at each, the
    scene's fixed parts and (manipulators) each palm's key frames."""
    traj = result.trajectory
    if not traj or len(traj.get("time", ())) < 2:
        raise ValueError("the run has no trajectory to animate (simulate with "
                         "record_trajectory=True)")
    t = np.asarray(traj["time"], dtype=float)
    order = np.argsort(t, kind="stable")
    t = t[order]
    span = float(t[-1] - t[0])
    count = int(min(MAX_FRAMES, max(2, math.ceil(span * FRAME_RATE) + 1)))
    frames = np.linspace(t[0], t[-1], count)
    at = lambda key: np.interp(frames, t, np.asarray(traj[key], dtype=float)[order])  # noqa: E731
    data = {"kind": spec.kind, "t": _round(frames, 4), "dt": float(span / max(count - 1, 1)),
            "x": _round(at("x") * MM, 2), "y": _round(at("y") * MM, 2),
            "outcome": _outcome_words(result)}
    if spec.kind == "stairs":
        data |= _stairs(spec, result, t, order, frames)
    else:
        data |= _manipulators(spec, result)
    return data


def _outcome_words(result) -> str:
    outcome = result.outcome
    if outcome.completed:
        return f"completed: {outcome.stages_passed} stages passed"
    f = outcome.failure
    return (f"failed after {outcome.stages_passed} stages: {f.kind} at stage {f.stage}"
            if f is not None else f"stopped after {outcome.stages_passed} stages")


def _stairs(spec, result, t, order, frames) -> dict:
    r = spec.scene.ball.radius
    omega = np.asarray(result.trajectory["omega"], dtype=float)[order]
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
    return {"radius": r * MM, "spin": _round(np.interp(frames, t, spin), 4), "steps": steps,
            "window": max(4.0 * tread, 8.0 * rise, 40 * r * MM, 1.0), "below": 0.0}


def _stairs_pitch(steps):
    """(tread, rise) of the first full step drawn, mm (steps[0] is the launch platform)."""
    if len(steps) >= 3:
        return steps[1][1] - steps[1][0], steps[1][2] - steps[2][2]
    return (steps[0][1] - steps[0][0], 0.0) if steps else (1.0, 0.0)


def _manipulators(spec, result) -> dict:
    from ..scenes.manipulators.sim.geometry import build_row

    design = spec.design_at()
    stages = max(len(result.stages), max((e.stage for e in result.events), default=1), 1)
    row = build_row(spec.scene, design, stages, spec.verification.offsets)
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


def _round(values, digits) -> list[float]:
    return [round(float(v), digits) for v in values]


def animation_html(data: dict) -> str:
    """The SVG element (id pdm-animation, data-frame, data-frames), its controls and the inline
    script that plays it from load (no network, no library)."""
    frames = len(data["t"])
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    return (f'<div class="anim"><svg id="{ELEMENT_ID}" data-frame="0" data-frames="{frames}" '
            'xmlns="http://www.w3.org/2000/svg" preserveAspectRatio="xMidYMid meet" '
            'role="img" aria-label="the simulated run"></svg>\n'
            '<div class="controls"><button id="pdm-play" type="button">pause</button> '
            f'<input id="pdm-slider" type="range" min="0" max="{frames - 1}" value="0" '
            'step="1"> <span id="pdm-time">t = 0.000 s</span></div>\n'
            f'<p class="note">{_escape(data["outcome"])}; {frames} frames, '
            f'{1e3 * data["dt"]:.1f} ms of simulated time each, played at real time.</p></div>\n'
            f'<script id="pdm-animation-data" type="application/json">'
            f"{payload}</script>\n"
            f"<script>\n{_SCRIPT}\n</script>\n")


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


_SCRIPT = r"""
(function () {
  "use strict";
  var NS = "http://www.w3.org/2000/svg";
  var D = JSON.parse(document.getElementById("pdm-animation-data").textContent);
  var svg = document.getElementById("pdm-animation");
  var slider = document.getElementById("pdm-slider");
  var button = document.getElementById("pdm-play");
  var label = document.getElementById("pdm-time");
  var n = D.t.length, frame = 0, playing = true, last = null, clock = 0;
  function el(name, attrs, parent) {
    var e = document.createElementNS(NS, name);
    for (var k in attrs) e.setAttribute(k, attrs[k]);
    (parent || world).appendChild(e);
    return e;
  }
  var xs = D.x.slice(), ys = D.y.slice(), pad = 0;
  if (D.kind === "stairs") {
    D.steps.forEach(function (s) { xs.push(s[0], s[1]); ys.push(s[2]); });
    pad = 2 * D.radius + 50;
  } else {
    D.palms.forEach(function (p) {
      xs.push(p.pivot[0] - D.link - D.palm_width / 2, p.pivot[0] + D.link + D.palm_width / 2);
      ys.push(p.pivot[1] - D.link, p.pivot[1] + D.link);
    });
    pad = D.body_height + 50;
  }
  var x0 = Math.min.apply(null, xs) - pad, x1 = Math.max.apply(null, xs) + pad;
  var y0 = Math.min.apply(null, ys) - pad, y1 = Math.max.apply(null, ys) + pad;
  // a long device: the view follows the object, D.window wide (the whole when it fits)
  var follow = x1 - x0 > 1.2 * D.window, aspect = 0.42;
  var viewW = follow ? D.window : x1 - x0, viewH = follow ? aspect * D.window : y1 - y0;
  function look(i) {
    if (!follow) { svg.setAttribute("viewBox", [x0, -y1, viewW, viewH].join(" ")); return; }
    var cx = Math.max(x0 + viewW / 2, Math.min(x1 - viewW / 2, D.x[i]));
    var cy = D.y[i] - D.below;
    svg.setAttribute("viewBox", [cx - viewW / 2, -(cy + viewH / 2), viewW, viewH].join(" "));
  }
  look(0);
  var world = document.createElementNS(NS, "g");
  world.setAttribute("transform", "scale(1,-1)");
  svg.appendChild(world);
  var thin = {"vector-effect": "non-scaling-stroke", "stroke-width": 1.5};
  function styled(extra) { var o = {}; for (var k in thin) o[k] = thin[k];
    for (var j in extra) o[j] = extra[j]; return o; }
  var lift = D.kind === "stairs" ? D.radius : 0;  // stairs: the path of the ball's centre
  var path = D.x.map(function (x, i) { return x + "," + (D.y[i] + lift); }).join(" ");
  el("polyline", styled({points: path, fill: "none", stroke: "#2ca02c",
                         "stroke-dasharray": "6 4", opacity: 0.6}));
  var draw;
  if (D.kind === "stairs") {
    var outline = [], bottom = Math.min.apply(null, D.steps.map(function (s) { return s[2]; }));
    bottom -= D.radius + 100;
    D.steps.forEach(function (s) { outline.push(s[0] + "," + s[2], s[1] + "," + s[2]); });
    outline.push(D.steps[D.steps.length - 1][1] + "," + bottom, D.steps[0][0] + "," + bottom);
    el("polygon", styled({points: outline.join(" "), fill: "#d9d9d9", stroke: "#333"}));
    var ball = el("g", {}), shown = Math.max(D.radius, viewW / 120);
    el("circle", styled({cx: 0, cy: 0, r: shown, fill: "#1f77b4", stroke: "#08306b"}), ball);
    el("line", styled({x1: 0, y1: 0, x2: shown, y2: 0, stroke: "#fff"}), ball);
    draw = function (i) {
      var deg = D.spin[i] * 180 / Math.PI;
      ball.setAttribute("transform", "translate(" + D.x[i] + "," + (D.y[i] + D.radius) +
                        ") rotate(" + deg + ")");
    };
  } else {
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
    draw = function (i) {
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
  function show(i) {
    frame = Math.max(0, Math.min(n - 1, i));
    draw(frame);
    look(frame);
    svg.setAttribute("data-frame", String(frame));
    slider.value = String(frame);
    label.textContent = "t = " + D.t[frame].toFixed(3) + " s";
  }
  function tick(now) {
    if (playing) {
      if (last !== null) clock += (now - last) / 1000;
      last = now;
      var next = Math.floor(clock / D.dt);
      if (next >= n) { clock = 0; next = 0; }
      if (next !== frame) show(next);
    }
    window.requestAnimationFrame(tick);
  }
  function setPlaying(on) {
    playing = on; last = null; clock = frame * D.dt;
    button.textContent = on ? "pause" : "play";
  }
  button.addEventListener("click", function () { setPlaying(!playing); });
  slider.addEventListener("input", function () { setPlaying(false); show(+slider.value); });
  show(0);
  window.requestAnimationFrame(tick);
})();
"""
