"""Compare two folders of pdm-design JSON documents (optimize, yield) key by key, timings aside:
`python results/json_diff.py BEFORE_DIR AFTER_DIR` prints one line per document (results/
seam_unchanged.md)."""
import json
import os
import sys

base, after = sys.argv[1], sys.argv[2]
SKIP = {"time", "build_time", "solve_time", "wall_time", "seconds", "ipopt_time", "total_time",
        "elapsed", "t_wall", "t_proc_total", "creation_time", "nlp_time", "check_time",
        "verify_time", "solver_creation_time"}


def walk(a, b, path, out):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in set(a) | set(b):
            if k in SKIP or k.endswith("_time") or k.endswith("time_s"):
                continue
            if k not in a or k not in b:
                out.append(f"{path}.{k}: only in {'after' if k in b else 'base'}")
                continue
            walk(a[k], b[k], f"{path}.{k}", out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{path}: length {len(a)} vs {len(b)}")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", out)
    elif a != b:
        out.append(f"{path}: {str(a)[:60]} vs {str(b)[:60]}")


for f in sorted(os.listdir(base)):
    if not f.endswith(".json"):
        continue
    try:
        a = json.load(open(os.path.join(base, f)))
    except Exception:
        print(f, "base: no JSON")
        continue
    try:
        b = json.load(open(os.path.join(after, f)))
    except Exception:
        print(f, "after: no JSON")
        continue
    out = []
    walk(a, b, "", out)
    print(f, "identical (timings aside)" if not out
          else f"{len(out)} differences: " + "; ".join(out[:6]))
