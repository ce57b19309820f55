"""The rocking row's builds run twice: by the event simulator (its phases, with time stepping
where no phase follows a contact) and time stepped from the feed to the end (sim/stepped.py,
every palm in the stepper, nothing handed to the phases): the two methods' yields, and how
often they agree build by build.

    python3 results/bench_stepped_row.py [--builds N] [--spec SPEC]

Prints the figures (results/bench_stepped_row.md keeps them with the command that made them)
and writes every build's two verdicts to bench_stepped_row.json (--out)."""

from __future__ import annotations

import argparse
import collections
import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _runs(args):
    spec_path, index = args
    from pdm_design.commands.yield_ import simulate_build_of_spec
    from pdm_design.scenes.manipulators.sim.run import Run
    from pdm_design.spec.loader import load_spec

    spec = load_spec(spec_path)
    design, stages = spec.design_at(), spec.verification.stages
    out = []
    for whole in (False, True):
        flight = Run._flight

        def stepped_from_the_feed(self, t0, x, y, vx, vy, stage, _flight=flight):
            if t0 == 0.0 and not self.events:
                return self._step_whole(t0, x, y, vx, vy)
            return _flight(self, t0, x, y, vx, vy, stage)

        if whole:
            Run._flight = stepped_from_the_feed
        try:
            start = time.process_time()
            result = simulate_build_of_spec(spec, spec_path, design, f"0:{index}", stages,
                                            accuracy=None)
            seconds = time.process_time() - start
        finally:
            Run._flight = flight
        failure = result.outcome.failure
        out.append((result.outcome.completed, failure.kind if failure else None, seconds))
    return index, out


def wilson(k, n, z=1.959963984540054):
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--builds", type=int, default=300)
    parser.add_argument("--spec", default=str(HERE / "rocking_row.toml"))
    parser.add_argument("--out", default=str(HERE / "bench_stepped_row.json"))
    args = parser.parse_args()
    spec = Path(args.spec)
    text = spec.read_text().replace("[verification]", "[verification]\nallow_skips = true", 1)
    skips = Path("/tmp") / f"{spec.stem}_skips.toml"
    skips.write_text(text)
    with ProcessPoolExecutor(2) as pool:
        rows = list(pool.map(_runs, [(str(skips), i) for i in range(args.builds)],
                             chunksize=4))
    Path(args.out).write_text(json.dumps(
        [{"build": i, "event_simulator": a[1] or "completed", "time_stepped": b[1] or "completed"}
         for i, (a, b) in rows], indent=0))
    n = len(rows)
    ok = [sum(r[1][m][0] for r in rows) for m in (0, 1)]
    agree = sum(r[1][0][0] == r[1][1][0] for r in rows)
    both = collections.Counter((r[1][0][1] or "completed", r[1][1][1] or "completed")
                               for r in rows if r[1][0][0] != r[1][1][0])
    cpu = [sum(r[1][m][2] for r in rows) for m in (0, 1)]
    lines = [f"builds {n} of {spec.name} with allow_skips (seed 0)", ""]
    for name, k, c in (("event simulator", ok[0], cpu[0]), ("time stepped from the feed", ok[1],
                                                            cpu[1])):
        lo, hi = wilson(k, n)
        lines.append(f"- {name}: {k} of {n} complete, {100 * k / n:.2f} % "
                     f"({100 * lo:.2f}-{100 * hi:.2f} %), {c:.0f} s of CPU")
    lines.append(f"- the same verdict (complete or not) on {agree} of {n} builds")
    for (a, b), count in both.most_common():
        lines.append(f"  - {count}: event simulator {a}, time stepped {b}")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
