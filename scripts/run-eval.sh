#!/usr/bin/env bash
# Runs paco_eval in dataset mode until it finishes, resuming after a crash: a solver that aborts
# the process (CBC/Clp assertions have been seen) is recorded as a failed case from paco_eval's
# started.log journal on the rerun. Stops on success or Ctrl-C.
#   scripts/run-eval.sh build/apps/paco_eval --dataset out/mfcad_val --split val ... -o out/eval
set -u
if [ $# -lt 2 ]; then
  echo "usage: $0 PATH/TO/paco_eval ARGS..." >&2
  exit 2
fi
while true; do
  "$@"
  rc=$?
  if [ $rc -eq 0 ] || [ $rc -eq 130 ] || [ $rc -eq 2 ]; then exit $rc; fi
  echo "paco_eval exited with $rc; resuming" >&2
done
