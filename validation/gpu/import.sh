#!/usr/bin/env bash
# Takes a GPU batch back (validation/gpu/run.sh on the device machine): unpacks FILES_AT/gpu.tgz.*
# into out/gpu_import/gpu/, imports its Ten Cate runs, its runs of E1 in the experiment's box and its
# beds into the work folders validation/imb/work/{ten_cate,experiment,fluidized_bed}/ and their records
# into validation/imb/results/*.json (the reports rebuilt), renders the seed's sedimentation into
# validation/sedimentation/sedimentation-41.{png,json} (with its summary.json), folds the kernels'
# rows (bench_kernels.txt, bench_{trt,mrt}.txt: validation/gpu/kernel_rows.py) and the coupled
# sweeps' (coupled_*.txt: validation/gpu/coupled_rows.py) into BENCHMARKS.md, and lists what goes
# by hand into BENCHMARKS.md (the passes of coupled_*.txt, bench_*.txt, suspension*/summary.json,
# dem_bench_*.txt) and into
# validation/lbm/REPORT.md (the "finer grids" sections of validate/ and validate_wake/REPORT.md).
#
#     bash validation/gpu/import.sh FILES_AT     # the folder the device tool put the files in
set -euo pipefail
cd "$(dirname "$0")/../.."
src=${1:?usage: bash validation/gpu/import.sh FILES_AT}
ls "$src"/gpu.tgz.* >/dev/null 2>&1 || { echo "no gpu.tgz.* in $src" >&2; exit 1; }
# The reports' charts need matplotlib and numpy: installed first where missing, so that a fresh
# machine does not stop half way, after the Ten Cate runs and before the tables are folded in.
if ! python3 -c "import matplotlib, numpy" 2>/dev/null; then
    python3 -m pip install --quiet --disable-pip-version-check -r validation/sedimentation/requirements.txt ||
        { echo "import.sh needs matplotlib and numpy: python3 -m pip install -r validation/sedimentation/requirements.txt" >&2; exit 1; }
fi
dest=out/gpu_import
rm -rf "$dest"
mkdir -p "$dest"
cat "$src"/gpu.tgz.* | tar xzf - -C "$dest"
g=$dest/gpu
echo "== batch.log"
cat "$g/batch.log"
if [ -d "$g/tencate" ]; then
    echo "== Ten Cate"
    python3 validation/imb/ten_cate.py import "$g/tencate"
fi
if [ -d "$g/experiment" ]; then
    echo "== Ten Cate E1 against the experiment"
    python3 validation/imb/experiment.py import "$g/experiment"
fi
if [ -d "$g/bed" ]; then
    echo "== fluidized bed"
    python3 validation/imb/fluidized_bed.py import "$g/bed" > /dev/null
    ls validation/imb/work/fluidized_bed
fi
if [ -d "$g/sedimentation" ]; then
    # Named after the run's scene: sedimentation-41, or sedimentation-small from prepare.sh --small.
    name=$(sed -n 's/^name = "\(.*\)"/\1/p' "$g/sedimentation/scene.toml")
    echo "== the seed's sedimentation: $name (validation/sedimentation/README.md)"
    cp "$g/sedimentation/summary.json" "validation/sedimentation/$name-summary.json"
    python3 validation/sedimentation/render.py "$g/sedimentation" --png "validation/sedimentation/$name.png" \
        --json "validation/sedimentation/$name.json" || echo "render.py failed" >&2
fi
if [ -f "$g/bench_kernels.txt" ]; then
    echo "== the kernels: per-cell against quads, each storage, into BENCHMARKS.md"
    python3 validation/gpu/kernel_rows.py "$g"
fi
if ls "$g"/coupled_*.txt >/dev/null 2>&1; then
    echo "== the coupled sweeps: each way of the covered cells, into BENCHMARKS.md"
    python3 validation/gpu/coupled_rows.py "$g"
fi
echo "== by hand: BENCHMARKS.md and validation/lbm/REPORT.md from"
find "$g" -maxdepth 2 \( -name 'bench_*.txt' -o -name 'coupled_*.txt' -o -name 'dem_bench_*.txt' \
    -o -name summary.json -o -name REPORT.md \) | sort
