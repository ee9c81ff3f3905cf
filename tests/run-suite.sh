#!/usr/bin/env bash
# The whole suite: once serially, then under mpirun with N ranks (default 2).
# Runs inside the image; `make test` calls it.
set -uo pipefail
ranks=${1:-2}
cd "$(dirname "$0")/.."
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH}
export logdir=${XDG_CACHE_HOME:-/tmp}/hfcdem-test-logs
mkdir -p "$logdir"
rm -f "$logdir"/*.xml "$logdir"/rank*.log

t0=$SECONDS
echo "== serial: python3 -m pytest"
python3 -m pytest -q tests --junitxml="$logdir/serial.xml"
serial=$?
echo "== serial suite: exit $serial in $((SECONDS - t0)) s"

t1=$SECONDS
echo "== parallel: mpirun -n $ranks python3 -m pytest (rank 0 shown, others in $logdir)"
# every rank runs the same tests; only rank 0 prints, the others log to files
mpirun -n "$ranks" bash -c '
  r=${OMPI_COMM_WORLD_RANK:-${PMIX_RANK:-0}}
  if [ "$r" = 0 ]; then exec python3 -m pytest -q --color=no tests --junitxml="$logdir/mpi.xml"
  else exec python3 -m pytest -q --color=no tests >"$logdir/rank$r.log" 2>&1; fi'
parallel=$?
if [ $parallel -ne 0 ]; then
  for f in "$logdir"/rank*.log; do echo "---- $f"; tail -40 "$f"; done
fi
echo "== parallel suite: exit $parallel in $((SECONDS - t1)) s"

# one closing line over both runs (rank 0's view of the parallel run)
python3 - "$logdir/serial.xml" "$logdir/mpi.xml" <<'PY'
import sys
import xml.etree.ElementTree as ET
n = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
for path in sys.argv[1:]:
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        continue
    for suite in root.iter("testsuite"):
        for key in n:
            n[key] += int(suite.get(key, 0))
failed = n["failures"] + n["errors"]
passed = n["tests"] - failed - n["skipped"]
print(f"suite: {passed} passed, {failed} failed, {n['skipped']} skipped")
PY

# pytest exits 5 when it collected nothing: that is a failure here too
[ $serial -eq 0 ] && [ $parallel -eq 0 ]
