"""The test suite's cost (not a test): wall and CPU time, peak memory per process, and the
collected tests. Figures in results/bench_test_suite.md.

    python results/bench_test_suite.py run [PYTEST ARGS]   # the default suite (~2.5 min idle)
    python results/bench_test_suite.py ids OUT              # node ids of default + slow suites

`run` runs `python3 -m pytest -q -p no:cacheprovider` under /usr/bin/time -v with
PDM_TEST_MEMLOG set (tests/conftest.py): each pytest process (the pytest-xdist workers and the
controller) writes its peak resident memory (ru_maxrss) to a log (kept at PDM_TEST_MEMLOG
when that is set, with each module's figures), summed here: the suite's peak memory is
at most that sum (the workers' peaks need not fall at the same moment). /usr/bin/time's own
"Maximum resident set size" is the largest single process of the tree, not a sum.
`ids` writes the sorted node ids of `pytest --collect-only` (distribution off) for the default
suite and for `-m slow`, to compare a branch's collected tests with another's.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIME_FIELDS = {
    "wall": r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)",
    "user": r"User time \(seconds\): (\S+)",
    "system": r"System time \(seconds\): (\S+)",
    "largest process (MB)": r"Maximum resident set size \(kbytes\): (\d+)",
}


def run(args: list[str]) -> None:
    with tempfile.TemporaryDirectory() as folder:
        log = Path(os.environ.get("PDM_TEST_MEMLOG") or Path(folder) / "memory.log")
        log.unlink(missing_ok=True)
        env = {**os.environ, "PDM_TEST_MEMLOG": str(log)}
        out = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-m", "pytest", "-q",
                              "-p", "no:cacheprovider", *args],
                             cwd=ROOT, env=env, capture_output=True, text=True)
        lines = log.read_text().splitlines() if log.exists() else []
    print(out.stdout[out.stdout.find("slowest"):][:4000] if "slowest" in out.stdout else "")
    summary = [ln for ln in out.stdout.splitlines() if re.search(r" (passed|failed)", ln)]
    print(summary[-1] if summary else out.stdout[-2000:])
    for name, pattern in TIME_FIELDS.items():
        found = re.search(pattern, out.stderr)
        value = found.group(1) if found else "?"
        if name.endswith("(MB)") and found:
            value = f"{int(value) / 1024:.0f}"
        print(f"{name}: {value}")
    peaks = {w: float(mb) for _, w, mb in (ln.split() for ln in lines if ln.startswith("peak "))}
    for worker, mb in sorted(peaks.items()):
        print(f"peak RSS {worker}: {mb:.0f} MB")
    print(f"peak RSS, sum over the pytest processes: {sum(peaks.values()):.0f} MB")


def ids(out: Path) -> None:
    found = []
    for marks in (["-m", "not slow"], ["-m", "slow"]):
        listed = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q",
                                 "-p", "no:cacheprovider", "-n", "0", *marks],
                                cwd=ROOT, capture_output=True, text=True).stdout
        found += [ln for ln in listed.splitlines() if "::" in ln]
    out.write_text("\n".join(sorted(found)) + "\n")
    print(f"{len(found)} node ids -> {out}")


if __name__ == "__main__":
    if sys.argv[1:2] == ["run"]:
        run(sys.argv[2:])
    elif sys.argv[1:2] == ["ids"] and len(sys.argv) == 3:
        ids(Path(sys.argv[2]))
    else:
        sys.exit(__doc__)
