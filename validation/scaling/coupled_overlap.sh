#!/bin/sh
# A coupled run on 2 MPI ranks with the halo exchange overlapped with the interior's update
# against the exchange after the whole step (BENCHMARKS.md, "The overlapped exchange of a coupled
# step on lavapipe"): coupled-weak-2.toml (32 x 32 x 64 cells, 16 spheres, blocks 1x1x2) with
# coupling.covered_cells = WAY and [parallel] overlap = true / false, alternated, ROUNDS rounds;
# prints each run's steps/s, fluid time, halo share per rank and summary.json's halo_overlapped.
# Usage (from the repository root, after cargo build --release -p lbm-server --features mpi):
#   sh validation/scaling/coupled_overlap.sh [WAYS (skip fused)] [ROUNDS (3)] [STEPS (600)]
set -e
ways=${1:-skip fused}
rounds=${2:-3}
steps=${3:-600}
dir=$(mktemp -d)
for way in $ways; do
    for overlap in true false; do
        sed -e "s/^timeout = 30.0/timeout = 30.0\ncovered_cells = \"$way\"/" \
            validation/scaling/coupled-weak-2.toml > "$dir/$way-$overlap.toml"
        printf '[parallel]\noverlap = %s\n' "$overlap" >> "$dir/$way-$overlap.toml"
    done
done
for round in $(seq "$rounds"); do
    for way in $ways; do
        for overlap in true false; do
            out="$dir/out-$way-$overlap-$round"
            load=$(cut -d' ' -f1 /proc/loadavg)
            mpirun --allow-run-as-root --oversubscribe -np 2 -x LP_NUM_THREADS=1 \
                target/release/lbm-server run "$dir/$way-$overlap.toml" --steps "$steps" --out "$out" \
                > "$out.log" 2>&1
            python3 -c "
import json
s = json.load(open('$out/summary.json'))
p = s['parallel']
print('$way overlap=$overlap round $round load $load: %.1f steps/s, fluid %.3f s, halo share %s, halo_overlapped %s'
      % (s['steps_per_second'], s['time_s']['fluid'], [round(x, 3) for x in p['halo_share']], p['halo_overlapped']))"
        done
    done
done
rm -r "$dir"
