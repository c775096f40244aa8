#!/bin/sh
# Scale measurements of `aeroform identify` (docs/SCALE.md). Usage: run.sh BIN [WORK_DIR]
# Writes the paper campaign (448 cases) at 10, 30, 60 s and one 10-million-row case, then
# measures peak RSS and wall time with /usr/bin/time -v, alternating per data set between
# glibc's default allocator settings and a fixed 1 MiB mmap threshold
# (MALLOC_MMAP_THRESHOLD_=1048576), so that both see the same load.
set -e
BIN=$(readlink -f "$1"); W=${2:-/tmp/props-scale}; HERE=$(dirname "$(readlink -f "$0")")
export W
mkdir -p "$W"; cd "$W"
for d in 10 30 60; do
  [ -d d$d ] || "$BIN" tunnel forced --model "$HERE/../../scenarios/plate-truth.model.toml" \
      --campaign paper --duration $d --out "$W/d$d"
done
[ -d m10 ] || python3 "$HERE/long_case.py" "$W/m10" 10000000
for ds in d10 d30 d60 m10; do
  "$HERE/measure.sh" "$BIN" glibc-default "$W/$ds"
  MALLOC_MMAP_THRESHOLD_=1048576 "$HERE/measure.sh" "$BIN" mmap1M "$W/$ds"
done
