#!/usr/bin/env bash
# Regenerate results/paper, results/tables, results/sheets, results/reports and
# results/bench_sweep.md (see results/README.md).
# Usage: results/regenerate.sh [paper] [tables] [sheets] [reports] [bench]
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 results/regenerate.py "$@"
