#!/usr/bin/env bash
# The 2D instruction gate of issue 36: instructions per particle-step of the 2D solver's step
# (cachegrind, one thread, the seed block of `solver/examples/profile_step.rs` at 2 mm cells,
# 31,250 particles), the difference of 24 and 12 timed steps so set-up is left out, with and
# without a crack, for the portable and the FMA kernel.
#
#   scripts/instructions-2d.sh BIN [BIN ...]
#
# BIN: a `profile_step` built with `cargo build --release -p fracture-solver --example
# profile_step` (copy it aside per commit to compare commits). Prints one line per binary and
# case.
set -euo pipefail
n=31250
count() {
  valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null "$@" 2>&1 \
    | grep "I *refs" | awk '{print $4}' | tr -d ,
}
for case in "portable" "fma" "crack portable" "crack fma"; do
  for bin in "$@"; do
    # shellcheck disable=SC2086
    a=$(count "$bin" 0.002 12 $case)
    # shellcheck disable=SC2086
    z=$(count "$bin" 0.002 24 $case)
    echo "$case  $bin  $(( (z - a) / (12 * n) )) instructions per particle-step"
  done
done
