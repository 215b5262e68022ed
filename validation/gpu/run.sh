#!/usr/bin/env bash
# Every GPU figure of the project in one call on the device machine (a machine start costs minutes
# of a short budget). Prepare it first on the development machine: bash validation/gpu/prepare.sh.
# On the device machine, from the repository root, with carry [".gl", ".gpu"]:
#
#     bash validation/gpu/run.sh 540      # seconds for the whole batch (default 540)
#
# The outputs are made in a scratch folder and packed at the end (or when the batch is stopped)
# into $OUT/gpu.tgz.aa, .ab, ... (pieces of 15 MiB: the device tool returns at most 8 files of 16
# MiB, none deeper than two folders) beside $OUT/batch.log; back here,
# `bash validation/gpu/import.sh FILES_AT` unpacks them and imports the runs. Inside: batch.log,
# system.txt, bench_kernels.txt (LBM-only, 256^3, BGK: the per-cell kernel and the quads', each
# with the populations in fp32, fp16s and fp16c, beside the copy bandwidth and the naive kernel),
# bench_{trt,mrt}.txt (the same in FP32, both kernels), bench_ranks_{1,2,4}.txt (256^3 cut over
# 1, 2 and 4 ranks sharing the device, the exchange overlapped and exposed; bench_ranks_4_fp16s.txt
# the same in FP16S, its messages 2 bytes a population), bench_ranks_coupled_{redo,skip,fused}.txt
# (the same on 2 ranks with 16^3 spheres), bench_walls.txt and bench_periodic.txt (the Ten Cate
# grid at 16 cells, 224 x 224 x 256, closed and periodic, one sphere, both ways of treating the
# covered cells, each pass timed: what a closed box costs), coupled_trt.txt (256 x 256 x 512, 1 to
# 32^3 particles, ratio to LBM-only, by CPU time beside LBM-only steps, time per pass, the covered
# cells fused, redone and skipped),
# coupled_seed_density.txt (lavapipe's sweep: 512 and 4096 particles on 64 x 64 x 128, by pass),
# coupled_atomic_list.txt (32^3, the list joined with one atomic per cell, not per subgroup),
# coupled_dense.txt (64^3 particles, a dense bed), coupled_dem.txt (1 and 32^3 particles, the
# host idle 1.1 ms a step as for a DEM), default/ (the default scene), suspension/ and
# suspension_substeps/ (32^3 beads settling, the whole program, free flight on and off:
# summary.json), sedimentation/ (the seed's 41^3 spheres settling, bounded: summary.json and a compact
# particles.csv), dem_bench_{suspension,bed,bed_skin}.txt (the DEM side alone on this machine's
# cores, 32^3 beads dilute and in a bed, the bed also with a thinner skin), suspension_auto/ (the
# kernels and the three ways of treating the covered cells timed on the run's first steps) and suspension_{redo,skip,fused}/ (each held throughout), tencate/<run>/ and
# bed/<run>/ (the scenes of .gpu/plan.txt: Ten Cate and the fluidized bed, held and free),
# validate/REPORT.md (random arrays at 18 and 24 cells) and
# validate_wake/REPORT.md (a held sphere at Re 200 and 300 at 24 and 32): their sections go into
# validation/lbm/REPORT.md. The steps run in order of priority; a step that would start with less
# time left than it needs is skipped and named in batch.log. Estimated from the H200 run of commit
# c641298 (LBM-only at 256^3 18,500 MLUPS, the coupled sweep at 500 steps filling 300 s): the
# coupled sweep at 100 steps 150-200 s (its limit 200), bench_kernels 30-60 s (eight lattices of
# 256^3 set up on the host, 2 rounds of 300 steps each well under a second; limit 90),
# bench_{trt,mrt} 15-30 s each (limit 60): the kernels' rows are in by about 6 minutes of the
# 9-minute call (run.sh 540, timeout_s 600), the rest as the budget allows.
set -u
cd "$(dirname "$0")/../.."
budget=${1:-540}
start=$(date +%s)
dest=${OUT:-out/gpu}
mkdir -p "$dest"
dest=$(cd "$dest" && pwd)
OUT=$(mktemp -d)/gpu
mkdir -p "$OUT"
# The outputs packed into $dest whatever ends the batch.
pack() {
    rm -f "$dest"/gpu.tgz.*
    tar czf - -C "$(dirname "$OUT")" gpu | split -b 15M - "$dest/gpu.tgz."
    cp "$OUT/batch.log" "$dest/" 2>/dev/null
    ls -l "$dest"
}
trap pack EXIT
elapsed() { echo $(($(date +%s) - start)); }
left() { echo $((budget - $(elapsed))); }
log() { echo "[$(elapsed) s] $*" | tee -a "$OUT/batch.log"; }

# step NAME NEED LIMIT COMMAND...: COMMAND (stdout and stderr to $OUT/NAME.txt) when at least NEED
# seconds are left, stopped by SIGINT (a clean stop: lbm-server writes its outputs) after LIMIT
# seconds or when the budget runs out. Returns COMMAND's exit status, 125 when skipped.
step() {
    local name=$1 need=$2 limit=$3
    shift 3
    if [ "$(left)" -lt "$need" ]; then
        log "skipped $name: $(left) s left, needs $need"
        return 125
    fi
    [ "$limit" -gt $(($(left) - 5)) ] && limit=$(($(left) - 5))
    log "start $name (limit $limit s): $*"
    mkdir -p "$(dirname "$OUT/$name")"
    timeout -s INT -k 10 "$limit" "$@" > "$OUT/$name.txt" 2>&1
    local code=$?
    log "end $name: exit $code"
    return $code
}

# compact DIR N: DIR/particles.csv cut to every Nth output step and the last (complete rows only),
# the columns validation/sedimentation/render.py reads (step,time,id,x,y,z) and positions to 6
# digits; DIR's .vtp series removed.
compact() {
    local f=$1/particles.csv
    rm -f "$1"/particles_*.vtp "$1/particles.pvd"
    [ -f "$f" ] || return 0
    local last
    last=$(awk -F, 'NF == 18 { s = $1 } END { print s }' "$f")
    awk -F, -v n="$2" -v last="$last" 'NR == 1 { print "step,time,id,x,y,z"; next }
        NF == 18 && (k == 0 || $1 != step) { step = $1; k++; keep = (k - 1) % n == 0 || step == last }
        NF == 18 && keep { printf "%s,%s,%s,%.5e,%.5e,%.5e\n", $1, $2, $3, $4, $5, $6 }' "$f" > "$f.compact"
    mv "$f.compact" "$f"
}

if ls .gl/*.deb >/dev/null 2>&1; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd
export NODEVICE_SELECT=1
bin=.gpu/bin
mode=$(cat .gpu/mode 2>/dev/null || echo full)
{
    date -u
    uname -a
    nproc
    free -g
    command -v nvidia-smi >/dev/null && nvidia-smi
} > "$OUT/system.txt" 2>&1

if [ "$mode" = small ]; then
    cube=32x32x32 tencate=32x32x32 coupled=32x32x64 counts=1,8,64 dense=512 dense_dem=64 steps=30
    # lavapipe runs the per-cell kernel at a tenth of the quads' speed or less
    kernel_steps=5
    seed_grid=32x32x64 seed_counts=64 ranks_particles=64
else
    cube=256x256x256 tencate=224x224x256 coupled=256x256x512 counts=1,8,64,512,4096,32768 dense=262144 dense_dem=32768 steps=300
    kernel_steps=$steps
    seed_grid=64x64x128 seed_counts=512,4096 ranks_particles=4096
fi
# Coupled, the seed's Fig. 5 sweep (issue 5's target: 90% of LBM-only at 32^3 particles; its own
# LBM-only row on the same grid): first, as the batch's most wanted figure (2026-12-05: skip with
# the four-cell quads, never run on a GPU).
step coupled_trt 90 200 $bin/lbm-server bench --grid $coupled --operator trt --particles $counts \
    --steps $((steps / 3)) --rounds 1 --reference none --passes --covered-cells all
# The lavapipe sweep at the seed's density (one sphere of 4 cells per 1024 cells: 512 on 64 x 64 x
# 128, and 4096 there, denser), LBM-only beside it, each pass timed (BENCHMARKS.md "The coupled
# step at the seed's density"): a few seconds on a GPU, the same passes as on lavapipe.
step coupled_seed_density 20 45 $bin/lbm-server bench --grid $seed_grid --operator trt --particles $seed_counts \
    --steps $((steps / 3)) --rounds 2 --passes --covered-cells all
# The kernels (issue 40): the per-cell kernel against the quads' kernels, each with the populations
# in fp32, fp16s and fp16c (FP16S >= 1.5x FP32 on a GPU), BGK, rounds alternating, beside the
# naive two-lattice kernel and the copy bandwidth of the same run (issue 3's target: 85% of it;
# on the H200 ours ran 0.79x the naive kernel), with the bytes per cell. import.sh folds its rows
# into BENCHMARKS.md.
step bench_kernels 40 90 $bin/lbm-server bench --grid $cube --operator bgk --steps $kernel_steps --rounds 2 \
    --per-cell --storage fp32,fp16s,fp16c
# TRT and MRT the same way in FP32, the per-cell kernel beside the quads'.
for op in trt mrt; do
    step bench_$op 30 60 $bin/lbm-server bench --grid $cube --operator $op --steps $kernel_steps --rounds 2 --per-cell
done
# Ranks sharing the device (issue 37): the same lattice cut over 1, 2 and 4 ranks that are threads
# of one process (no MPI on the device machine), each with its own device handle, the halos through
# the host as between MPI ranks: what the exchange costs on a GPU (halo bytes, share of the step),
# overlapped with the interior's update and exposed after the whole step, each beside the blocks
# stepped without the exchange (`--exchange both`: the exposed exchange per step of each).
step bench_ranks_1 15 45 $bin/lbm-server bench --grid $cube --operator bgk --steps $kernel_steps --rounds 2 \
    --thread-ranks 1
for r in 2 4; do
    step bench_ranks_$r 20 60 $bin/lbm-server bench --grid $cube --operator bgk --steps $kernel_steps --rounds 2 \
        --thread-ranks $r --exchange both
done
step bench_ranks_4_fp16s 20 60 $bin/lbm-server bench --grid $cube --operator bgk --steps $kernel_steps --rounds 2 \
    --thread-ranks 4 --exchange both --storage fp16s
# The coupled step on 2 ranks sharing the device, 16^3 spheres, the covered cells redone (what
# "auto" takes on ranks), skipped and fused: the exchange overlapped with the interior's update against the exchange after the whole
# step (lbm-server/src/lbm/imb/by_region.rs).
for way in redo skip fused; do
    step bench_ranks_coupled_$way 20 60 $bin/lbm-server bench --grid $cube --operator bgk --steps $kernel_steps \
        --rounds 2 --thread-ranks 2 --particles $ranks_particles --covered-cells $way --exchange both
done
# A closed box against a periodic one on the Ten Cate grid at 16 cells, one sphere, both ways of
# treating the covered cells, by pass (2026-12-04: the whole program's fluid step ran at 2200
# MLUPS there, the periodic bench's at 11800-13500).
for faces in walls periodic; do
    step bench_$faces 30 60 $bin/lbm-server bench --grid $tencate --faces $faces --operator trt --particles 1 \
        --steps $((steps / 2)) --rounds 1 --reference none --passes --covered-cells both
done
# The coupled sweep's 32^3 row with one atomic per covered cell on the list's counter instead of one per
# subgroup (the default on a GPU since 2026-12-04): what the subgroups gain, by pass.
LBM_NO_SUBGROUPS=1 step coupled_atomic_list 30 60 $bin/lbm-server bench --grid $coupled --operator trt \
    --particles ${counts##*,} --steps $((steps / 3)) --rounds 1 --reference none --passes --covered-cells redo
# A dense bed: 64^3 spheres of 4 cells 4 x 4 x 8 cells apart, half the cells covered, both ways.
step coupled_dense 40 60 $bin/lbm-server bench --grid $coupled --operator trt --particles $dense \
    --steps $((steps / 15)) --rounds 1 --reference none --covered-cells all
# The coupled step with the host idle 1.1 ms after each step's loads, as for the DEM's step of 32^3
# beads flown on this machine's cores (2026-12-04): the redo's fluid kernels run meanwhile, the
# fused ones cannot (the lockstep row waits as long after each fluid step).
step coupled_dem 40 60 $bin/lbm-server bench --grid $coupled --operator trt --particles 1,$dense_dem \
    --steps $((steps / 3)) --rounds 1 --reference none --covered-cells all --dem-ms 1.1
# The default scene, the whole coupled program (DEM process and lockstep included).
step default/log 30 60 $bin/lbm-server run .gpu/default.toml --out "$OUT/default"
rm -rf "$OUT/default/fields"
# The whole program at 32^3 particles (a dilute suspension on the coupled sweep's grid): where the
# time goes (summary.json time_s), the DEM flying its steps and sub-stepped throughout.
for s in suspension suspension_substeps; do
    step $s/log 40 120 $bin/lbm-server run .gpu/$s.toml --out "$OUT/$s"
    rm -f "$OUT/$s/particles.csv" "$OUT/$s"/particles_*.vtp "$OUT/$s/particles.pvd"
done
# The seed's multi-particle sedimentation (section 3.2, Fig. 3: 41^3 spheres of 4 cells on 288 x
# 288 x 576 cells, TRT at tau 0.6), the whole program for a bounded time: its step at the seed's
# size (summary.json) and the first of its 0.2 s (validation/sedimentation/README.md). particles.csv
# kept compact: every second output (5 ms apart) and the last, step,time,id,x,y,z.
step sedimentation/log 60 120 $bin/lbm-server run .gpu/sedimentation.toml --out "$OUT/sedimentation"
compact "$OUT/sedimentation" 2
# The DEM side alone on this machine's cores, the fluid a stand-in (dem-client bench): 32^3 beads
# dilute (flown) and in a bed (every bead in the DEM steps), free flight on and off. With the
# fluid's step above, what a whole coupled step costs between these two extremes. The bed's 12
# fluid steps hold a trial of the two ways of an island of every bead (its "timed" line: through
# the island's world or as the whole world, on this machine's cores).
step dem_bench_suspension 20 60 $bin/dem-client bench .gpu/suspension.toml --steps 40 --free-flight both
step dem_bench_bed 20 90 $bin/dem-client bench .gpu/bed.toml --steps 12 --free-flight both
step dem_bench_bed_skin 15 60 $bin/dem-client bench .gpu/bed_skin.toml --steps 12 --free-flight on
# The suspension with its start-up trial of the kernels and of the three ways of treating the
# covered cells (its log's "kernels timed" and "covered cells timed" lines, and summary.json's
# trial), and with each way held throughout (the kernels still timed): the whole program's
# answer, the DEM's step included, to which kernel and way a GPU should take, and what a trial
# costs (the kernels built during the run).
for way in auto redo skip fused; do
    step suspension_$way/log 30 60 $bin/lbm-server run .gpu/suspension_$way.toml --out "$OUT/suspension_$way"
    rm -f "$OUT/suspension_$way/particles.csv" "$OUT/suspension_$way"/particles_*.vtp "$OUT/suspension_$way/particles.pvd"
done
# Random arrays at the fluidized bed's voidage at 18 and 24 cells per diameter (lavapipe: 6-12):
# whether their drag at the bed's Re converges to Tenneti et al.'s (validation/lbm/REPORT.md).
[ "$mode" = small ] || step validate/log 60 150 $bin/lbm-server validate --out "$OUT/validate" --only random-drag-fine
# Ten Cate, E1 in the experiment's box (exp_*) and the fluidized bed (bed_*), in the order of
# .gpu/plan.txt.
while read -r name _; do
    [ -f ".gpu/scenes/$name/scene.toml" ] || continue
    kind=tencate
    case $name in bed_*) kind=bed ;; exp_*) kind=experiment ;; esac
    dir="$OUT/$kind/$name"
    step "$kind/$name/log" 20 300 $bin/lbm-server run ".gpu/scenes/$name/scene.toml" --out "$dir"
    code=$?
    [ "$code" -ne 125 ] && echo "$code" > "$dir/exit_code" && cp ".gpu/scenes/$name/scene.toml" "$dir/"
    rm -rf "$dir/fields" "$dir"/particles_*.vtp "$dir/particles.pvd"
done < .gpu/plan.txt
# A sphere held in a stream at Re 200 and 300 at 24 and 32 cells per diameter (lavapipe: 6-16):
# whether its drag keeps falling as 1 / d towards Schiller-Naumann (validation/lbm/REPORT.md).
[ "$mode" = small ] || step validate_wake/log 60 150 $bin/lbm-server validate --out "$OUT/validate_wake" --only wake-drag-fine
log "done"
