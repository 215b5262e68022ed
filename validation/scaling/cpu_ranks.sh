#!/bin/bash
# Strong and weak scaling of `lbm-server bench` on CPU ranks (Mesa lavapipe, one llvmpipe thread per
# rank), as BENCHMARKS.md "CPU ranks on lavapipe" reports it. Build first:
#   cargo build --release -p lbm-server --features mpi
# Usage: bash validation/scaling/cpu_ranks.sh [ROUNDS_OF_THE_SERIES]   (prints the bench's lines)
set -e
cd "$(dirname "$0")/../.."
M="mpirun --allow-run-as-root --oversubscribe -x LP_NUM_THREADS=1 -x NODEVICE_SELECT=1"
B=target/release/lbm-server
for _ in $(seq "${1:-1}"); do
  # strong: 64x64x64 on 1, 2, 4 ranks; weak: 64x64x32 per rank (1x1x1, 1x1x2, 1x1x4 blocks)
  for spec in "1 64x64x64" "2 64x64x64" "4 64x64x64" "1 64x64x32" "2 64x64x64" "4 64x64x128"; do
    set -- $spec
    echo "=== $1 rank(s), grid $2, load $(cut -d' ' -f1 /proc/loadavg)"
    $M -np "$1" $B bench --grid "$2" --steps 40 --rounds 2 2>&1 | grep -E '^(grid|rank|total| +[0-9])'
  done
done
