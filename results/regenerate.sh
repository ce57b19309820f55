#!/usr/bin/env bash
# Regenerate results/paper, results/tables, results/sheets and results/bench_sweep.md
# (see results/README.md). Usage: results/regenerate.sh [paper] [tables] [sheets] [bench]
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 results/regenerate.py "$@"
