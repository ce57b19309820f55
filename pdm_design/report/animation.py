"""The animated run of a report page: the simulator's recorded trajectory as plain data for the
page's script, and the SVG element and script that play it.

Frames are uniform in time (FRAME_RATE a second of simulated time, at most MAX_FRAMES: longer
runs are played with a coarser step), the object's place interpolated between the simulator's
samples. What is drawn is the scene's (Scene.animation: scenes/<kind>/animation.py): its part of
the page's data, and its drawing as a JavaScript object expression that the one player here
calls:

- `extent(D, xs, ys)`: push the x and y (mm) of every fixed part onto xs and ys (the view holds
  them all) and return the padding (mm) around them;
- `lift(D)`: how far above the recorded (x, y) the path is drawn (mm; 0: as recorded);
- `build(D, el, styled, view)`: create the scene's SVG elements with `el(name, attrs, parent)`
  (parent: the world group, y up, when left out) and `styled(attrs)` (attrs with a thin,
  non-scaling stroke), view {width, height} in mm, and return `draw(i)`, which places them at
  frame i (D.t[i], D.x[i], D.y[i], and the scene's own data).

D is the page's data: kind, t (s), dt, x and y (mm) of the object at each frame, outcome, and the
scene's keys, among them `window` (the view's width, mm, when the device is longer) and `below`
(how far under the object the view's centre is, mm).

Coordinates are millimetres, y up; the SVG flips y. A device longer than the page's window is
shown through a window that follows the object.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

FRAME_RATE = 30.0     # frames a second of simulated time (played at real time)
MAX_FRAMES = 1500
ELEMENT_ID = "pdm-animation"
MM = 1e3


@dataclass(frozen=True)
class Timeline:
    """The run's recorded samples sorted by time (`times`, s; `order`, the indices that sort
    them) and the animation's frame times (`frames`, s)."""

    times: np.ndarray
    order: np.ndarray
    frames: np.ndarray

    def sorted(self, values) -> np.ndarray:
        """A recorded trajectory column in time order."""
        return np.asarray(values, dtype=float)[self.order]

    def at(self, values) -> np.ndarray:
        """A recorded trajectory column at the frame times (linear interpolation)."""
        return np.interp(self.frames, self.times, self.sorted(values))


@dataclass(frozen=True)
class Animation:
    """data: plain data for the page (JSON); script: the scene's drawing, a JavaScript object
    expression {extent, lift, build} (the module's docstring)."""

    data: dict
    script: str


def animation(spec, result) -> Animation:
    """The page's data (frame times and the object's place at each, and the scene's part) and
    the scene's drawing script."""
    from ..plugin import of

    traj = result.trajectory
    if not traj or len(traj.get("time", ())) < 2:
        raise ValueError("the run has no trajectory to animate (simulate with "
                         "record_trajectory=True)")
    t = np.asarray(traj["time"], dtype=float)
    order = np.argsort(t, kind="stable")
    t = t[order]
    span = float(t[-1] - t[0])
    count = int(min(MAX_FRAMES, max(2, math.ceil(span * FRAME_RATE) + 1)))
    timeline = Timeline(t, order, np.linspace(t[0], t[-1], count))
    data = {"kind": spec.kind, "t": rounded(timeline.frames, 4),
            "dt": float(span / max(count - 1, 1)),
            "x": rounded(timeline.at(traj["x"]) * MM, 2),
            "y": rounded(timeline.at(traj["y"]) * MM, 2), "outcome": _outcome_words(result)}
    scene = of(spec).animation(spec, result, timeline)
    return Animation(data | scene.data, scene.script)


def animation_data(spec, result) -> dict:
    """Plain data for the page's script (animation(spec, result).data)."""
    return animation(spec, result).data


def _outcome_words(result) -> str:
    outcome = result.outcome
    if outcome.completed:
        return f"completed: {outcome.stages_passed} stages passed"
    f = outcome.failure
    return (f"failed after {outcome.stages_passed} stages: {f.kind} at stage {f.stage}"
            if f is not None else f"stopped after {outcome.stages_passed} stages")


def generic_animation(result) -> Animation:
    """A scene without its own animation: the object as a dot on its path, the whole in view."""
    xs = result.trajectory["x"]
    width = (max(xs) - min(xs)) * MM
    return Animation({"window": 2.0 * width + 200.0, "below": 0.0}, GENERIC_SCRIPT)


GENERIC_SCRIPT = r"""{
  extent: function (D, xs, ys) { return 50; },
  lift: function (D) { return 0; },
  build: function (D, el, styled, view) {
    var dot = el("circle", styled({r: Math.max(view.width / 120, 1), fill: "#1f77b4",
                                   stroke: "#08306b"}));
    return function (i) { dot.setAttribute("cx", D.x[i]); dot.setAttribute("cy", D.y[i]); };
  }
}"""


def rounded(values, digits) -> list[float]:
    """Plain floats rounded to `digits` decimals (the page's JSON)."""
    return [round(float(v), digits) for v in values]


def animation_html(shown: Animation) -> str:
    """The SVG element (id pdm-animation, data-frame, data-frames), its controls and the inline
    script that plays it from load (no network, no library)."""
    data = shown.data
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
            f"<script>\n{_SCRIPT.replace('SCENE_SCRIPT', shown.script)}\n</script>\n")


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
  var scene = SCENE_SCRIPT;
  var xs = D.x.slice(), ys = D.y.slice(), pad = scene.extent(D, xs, ys);
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
  var lift = scene.lift(D);  // e.g. a round object's path drawn at its centre
  var path = D.x.map(function (x, i) { return x + "," + (D.y[i] + lift); }).join(" ");
  el("polyline", styled({points: path, fill: "none", stroke: "#2ca02c",
                         "stroke-dasharray": "6 4", opacity: 0.6}));
  var draw = scene.build(D, el, styled, {width: viewW, height: viewH});
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
