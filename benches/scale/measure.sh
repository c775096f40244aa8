#!/bin/sh
# usage: measure.sh BIN LABEL DATASET... ; prints one line per data set
BIN=$1; LABEL=$2; shift 2
for ds in "$@"; do
  out=${W:-/tmp/props-scale}/out-$LABEL-$(basename $ds)
  rm -rf $out
  /usr/bin/time -v $BIN identify $ds --out $out --quiet --timing-json $out.timing.json 2> $out.time.txt
  rc=$?
  rss=$(grep "Maximum resident" $out.time.txt | awk '{print $6}')
  wall=$(grep "Elapsed (wall" $out.time.txt | awk '{print $8}')
  bytes=$(du -sb $ds/cases | cut -f1)
  echo "$LABEL $(basename $ds) rc=$rc csv_bytes=$bytes peak_rss_kB=$rss wall=$wall timing=$(tr -d ' \n' < $out.timing.json 2>/dev/null)"
done
