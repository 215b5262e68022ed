#!/usr/bin/env bash
# Prepares the GPU batch (validation/gpu/run.sh) on the development machine, which has no GPU: the
# Vulkan loader packages in .gl/, the stripped release binaries and the Ten Cate scenes in .gpu/
# (both kept out of git by .gitignore, carried to the device machine with
# carry [".gl", ".gpu"]: about 20 MB of the 64 MiB allowed).
#
#     bash validation/gpu/prepare.sh           # the full batch (H100/H200-class GPU)
#     bash validation/gpu/prepare.sh --small   # a few-minute version that runs on lavapipe (a check of the scripts)
set -euo pipefail
cd "$(dirname "$0")/../.."
small=false
[ "${1:-}" = "--small" ] && small=true
if ! ls .gl/*.deb >/dev/null 2>&1; then
    mkdir -p .gl /tmp/amd64/partial
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    apt-get $o update -qq
    (cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi
cargo build --release --bins
rm -rf .gpu
mkdir -p .gpu/bin .gpu/scenes
cp target/release/lbm-server target/release/dem-client .gpu/bin/
strip .gpu/bin/*
cp validation/scenes/default.toml .gpu/
# The whole program at the seed's 32^3 particles (a copy of 4^3 beads in a 40 x 40 x 80 mm box for
# --small), and the same with the DEM sub-stepped throughout (free flight off).
if $small; then
    sed 's/max = \[0.256, 0.256, 0.512\]/max = [0.040, 0.040, 0.080]/; s/count = \[32, 32, 32\]/count = [4, 4, 4]/;
         s/origin = \[0.0071, 0.0071, 0.128\]/origin = [0.0071, 0.0071, 0.024]/' \
        validation/scenes/suspension.toml > .gpu/suspension.toml
else
    cp validation/scenes/suspension.toml .gpu/
fi
sed 's/^free_flight = true/free_flight = false/' .gpu/suspension.toml > .gpu/suspension_substeps.toml
# The same suspension timing the kernels and the three ways of treating the covered cells on its
# first steps ("auto", the default, named), and with each way held throughout.
for way in auto redo skip fused; do
    sed "s/^\[coupling\]/[coupling]\ncovered_cells = \"$way\"/" .gpu/suspension.toml > .gpu/suspension_$way.toml
done
# The seed's sedimentation (section 3.2: 41^3 spheres on 288 x 288 x 576 cells); for --small a
# stand-in of 5^3 spheres 7 cells apart on 35 x 35 x 70 cells, 0.5 ms (218 steps).
if $small; then
    sed 's/^name = .*/name = "sedimentation-small"/; s/^count = .*/count = [5, 5, 5]/;
         s/^max = .*/max = [0.0002905, 0.0002905, 0.000581]/; s/^spacing = .*/spacing = 5.81e-5/;
         s/^origin = .*/origin = [2.905e-5, 2.905e-5, 3.1955e-4]/;
         s/^duration = .*/duration = 0.0005/; s/^time_interval = .*/time_interval = 0.0001/' \
        validation/scenes/sedimentation-41.toml > .gpu/sedimentation.toml
else
    cp validation/scenes/sedimentation-41.toml .gpu/sedimentation.toml
fi
# The DEM side alone (dem-client bench) on a bed of 32^3 beads in contact (4^3 for --small).
if $small; then
    sed 's/count = \[32, 32, 32\]/count = [4, 4, 4]/' validation/scenes/bed.toml > .gpu/bed.toml
else
    cp validation/scenes/bed.toml .gpu/
fi
# The same bed with a thinner Verlet skin (0.5 mm instead of half a radius): 95k listed pairs
# instead of 280k (docs/dem.md, "Broad phase").
sed 's/^\[particles\]/[dem]\nskin = 0.0005\n\n[particles]/' .gpu/bed.toml > .gpu/bed_skin.toml
# One line per scene, in the order run.sh runs them (its priority): name, cells, tau, steps.
scenes() { python3 validation/imb/ten_cate.py scenes .gpu/scenes "$@" >> .gpu/plan.txt; }
# Ten Cate E1 in the experiment's box against its measured curves (validation/imb/experiment.py).
experiment() { python3 validation/imb/experiment.py scenes .gpu/scenes "$@" >> .gpu/plan.txt; }
# The fluidized bed at 10 and 15 cells per diameter (validation/imb/fluidized_bed.py GPU_CASES),
# after the bed held still at 12 and 18 (GPU_HELD_CELLS: a tenth of the cost).
beds() {
    python3 validation/imb/fluidized_bed.py held-scenes .gpu/scenes > .gpu/beds.txt
    python3 validation/imb/fluidized_bed.py scenes .gpu/scenes >> .gpu/beds.txt
}
if $small; then
    echo small > .gpu/mode
    scenes 3 --cases E3 E4 --sim-time 0.3
    experiment 3 --sim-time 0.3
    # One bed, 20 steps (a check that its outputs come back and import).
    beds
    head -n 1 .gpu/beds.txt >> .gpu/plan.txt
    for d in .gpu/scenes/bed_*; do
        grep -q "^$(basename "$d") " .gpu/plan.txt || rm -rf "$d"
    done
    sed -i 's/^steps = .*/steps = 20/' .gpu/scenes/bed_*/scene.toml
else
    echo full > .gpu/mode
    # Ten Cate E1-E4 beyond what lavapipe can hold, in closed boxes about twice the experiment's
    # width, tau held at its 12-cells value (the Mach number falls as 1/N): E1 and E2 at the Mach
    # numbers that give their N = 12 wide-box tau (1.20 and 1.01), E3 and E4 at Mach 0.1 as all
    # their runs (tau 0.74 / 0.86 and 0.59 / 0.63 at 16 / 24 cells).
    # 16 cells per diameter: 210 x 210 x 240 mm, 224 x 224 x 256 cells (200 mm is not a whole number of cells).
    scenes 16 --cases E1 --mach 0.0375 --width 210 --height 240
    scenes 16 --cases E2 --mach 0.075 --width 210 --height 240
    scenes 16 --cases E3 E4 --width 210 --height 240
    # E1 in the experiment's box at tau 1.03 (as 9 cells at Mach 0.05): 15 cells, 1.6e10
    # cell-steps (run on lavapipe in 19 min on 2026-12-05, so left out below as imported).
    experiment 15 --mach 0.03
    beds
    cat .gpu/beds.txt >> .gpu/plan.txt
    # 24 cells per diameter: 200 x 200 x 240 mm, 320 x 320 x 384 cells; E3 and E4 first (2.8e11
    # cell-steps each, against 5.7e11 and 1.1e12 for E2 and E1).
    scenes 24 --cases E3 E4 --width 200 --height 240
    scenes 24 --cases E2 --mach 0.05 --width 200 --height 240
    scenes 24 --cases E1 --mach 0.025 --width 200 --height 240
    # E1 in the experiment's box at 24 cells, tau 1.03: 160 x 160 x 256 cells, 1.7e11 cell-steps.
    experiment 24 --mach 0.01875
    # Runs already imported are left out: a Ten Cate run that completed (its record in
    # validation/imb/results/ten_cate.json, experiment.json for exp_NAME), a bed that ran, to its end
    # or to its blow-up (results/fluidized_bed.json, NAME without bed_).
    imported() {
        python3 validation/imb/results.py imported "$1"
    }
    while read -r name rest; do
        if imported "$name"; then
            echo "already imported, left out: $name"
            rm -rf ".gpu/scenes/$name"
        else
            echo "$name $rest"
        fi
    done < .gpu/plan.txt > .gpu/plan.new
    grep -v '^already imported' .gpu/plan.new > .gpu/plan.txt
    grep '^already imported' .gpu/plan.new || true
    rm .gpu/plan.new
fi
cat .gpu/plan.txt
du -sh .gl .gpu
echo "now: run with carry [\".gl\", \".gpu\"] and the command 'bash validation/gpu/run.sh 540' (timeout_s 600),"
echo "then: bash validation/gpu/import.sh FILES_AT"
