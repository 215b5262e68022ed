#!/usr/bin/env python3
"""Weak-scaling model of lbm-server's fluid on several GPUs, from its halo bytes and link bandwidths.

Each rank holds a block of B^3 cells (periodic box, blocks as `choose_blocks` cuts them: 2 ranks
1x1x2, 4 ranks 1x2x2, 8 ranks 2x2x2, 16 ranks 2x2x4, 64 ranks 4x4x4), and a ghost layer at each cut
face, which it updates too. Per step and cut axis the halo moves 5 populations per face cell across
each of the block's two faces (lbm-server/src/parallel/halo.rs), as the storage holds them: 4 bytes
each in FP32, 2 in FP16S/FP16C (--storage fp16: its MLUPS FP32's times --fp16-speedup, FluidX3D's
published FP16S/FP32 ratio on the H200 by default, ours not yet measured on a GPU). Staged through the
host, as lbm-server does it, a face goes device -> host (PCIe), rank -> rank (the link) and host ->
device (PCIe), one axis after the other, each axis paying a fixed latency (a submission, a map and
an MPI round).

Exposed (`[parallel] overlap = false`), the exchange follows the whole step: step = compute +
exchange. Overlapped (the default), the shell (each cut face's ghost layer and the layer next to
it) is updated first, then per cut axis the exchange runs while the device updates one part of the
interior (the interior cut into as many parts as cut axes). The staging's copies stay on the
device's queue (the pack's copy to the host before the part, the upload after it); the link and
the latency run on the host and the network while the device updates the part: step = shell + sum
over the cut axes of (staging + max(interior part, link + latency)), the exposed exchange per axis
staging + max(0, link + latency - interior part).

With --copies-beside the staging's copies run beside the interior's kernels too (a device whose
copy engines take them: not what one wgpu queue promises).

Usage: python3 validation/scaling/model.py [--block 256[,512...]] [--storage fp32[,fp16]]
       [--mlups 18100] [--fp16-speedup 1.59] [--latency-us 30] [--copies-beside]
"""
import argparse

GB = 1e9
# Effective bandwidths per direction [bytes/s].
PCIE = {"PCIe 4 x16": 25 * GB, "PCIe 5 x16": 50 * GB}
LINKS = {
    "same node (host memory)": 100 * GB,
    "InfiniBand HDR (200 Gb/s)": 25 * GB,
    "InfiniBand NDR (400 Gb/s)": 50 * GB,
}
NVLINK = 450 * GB  # H100 SXM NVLink 4, per direction: device to device, no host staging
BLOCKS = {1: (1, 1, 1), 2: (1, 1, 2), 4: (1, 2, 2), 8: (2, 2, 2), 16: (2, 2, 4), 64: (4, 4, 4)}


def halo_time(block, ranks, stage, link, latency, bytes_each=4):
    """Seconds per step and cut axis of one rank's halo exchange (two faces) of populations of
    `bytes_each` bytes: the staging through the host (device -> host and host -> device, on the
    device's queue) and the rest (the link and the fixed latency, on the host); the cut axes, and
    the bytes a rank sends per step."""
    face_bytes = 5 * bytes_each * block * block
    cut = sum(1 for b in BLOCKS[ranks] if b > 1)
    staging = 4 * face_bytes / stage if stage else 0.0
    return staging, face_bytes / link + latency, cut, cut * 2 * face_bytes


def cells(block, cut):
    """A rank's cells with its ghost layers, and those of the shell (ghost and next layers)."""
    local = block ** (3 - cut) * (block + 2) ** cut
    interior = block ** (3 - cut) * (block - 2) ** cut
    return local, local - interior


def step_times(block, ranks, stage, link, latency, cell_time, copies_beside=False, bytes_each=4):
    """Seconds per step of one rank, exposed and overlapped. Overlapped, each axis's staging stays
    on the device's queue (the pack's copy to the host before the interior part, the upload after
    it), unless `copies_beside` (copy engines running them beside the interior's kernels); the
    link and the latency hide behind the interior part."""
    staging, wire, cut, _ = halo_time(block, ranks, stage, link, latency, bytes_each)
    if copies_beside:
        staging, wire = 0.0, wire + staging
    local, shell = cells(block, cut)
    exposed = local * cell_time + cut * (staging + wire)
    part = (local - shell) * cell_time / cut
    overlapped = shell * cell_time + cut * (staging + max(part, wire))
    return exposed, overlapped


def table(block, storage, a, latency):
    """The efficiencies of blocks of `block`^3 cells with `storage` on every path and rank count."""
    bytes_each, mlups = (4, a.mlups) if storage == "fp32" else (2, a.mlups * a.fp16_speedup)
    cell_time = 1 / (mlups * 1e6)
    compute = block**3 * cell_time
    print(f"block {block}^3 per GPU, {storage}, {mlups:.0f} MLUPS per GPU: {compute * 1e3:.3f} ms per step")
    print("weak-scaling efficiency (one GPU's time per step / the rank's), exposed | overlapped")
    ranks = [2, 4, 8, 16, 64]
    print(f"{'path':48}" + "".join(f"{n:>14}" for n in ranks))
    paths = [(f"{pcie} + {name}", PCIE[pcie], bw) for pcie in PCIE for name, bw in LINKS.items()]
    paths.append(("NVLink 4 device to device (no staging)", None, NVLINK))
    for name, stage, link in paths:
        row = []
        for n in ranks:
            exposed, overlapped = step_times(block, n, stage, link, latency, cell_time, a.copies_beside, bytes_each)
            row.append(f"{100 * compute / exposed:5.0f}% |{100 * compute / overlapped:4.0f}%")
        print(f"{name:48}" + "".join(f"{c:>14}" for c in row))
    staging, wire, cut, sent = halo_time(block, 8, PCIE["PCIe 4 x16"], LINKS["same node (host memory)"], latency, bytes_each)
    local, shell = cells(block, cut)
    part = (local - shell) * cell_time / cut
    print(
        f"at 8 ranks (2x2x2): {sent / 1e6:.2f} MB sent per rank and step; over PCIe 4 on one node per "
        f"cut axis {staging * 1e3:.3f} ms of staging and {wire * 1e3:.3f} ms of link and latency, "
        f"against {part * 1e3:.3f} ms of interior part"
    )


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--block", default="256", help="cells per block edge (a list: 256,512)")
    p.add_argument("--storage", default="fp32", help="fp32, fp16 or both: fp32,fp16")
    p.add_argument("--mlups", type=float, default=18100.0, help="one GPU's FP32 MLUPS (H200, BENCHMARKS.md)")
    p.add_argument("--fp16-speedup", type=float, default=36610 / 23056,
                   help="FP16's MLUPS over FP32's (default FluidX3D's FP16S/FP32 on the H200)")
    p.add_argument("--latency-us", type=float, default=30.0, help="fixed cost per cut axis and step [us]")
    p.add_argument("--copies-beside", action="store_true",
                   help="the staging copies run beside the interior's kernels (copy engines)")
    a = p.parse_args()
    for storage in a.storage.split(","):
        for block in a.block.split(","):
            table(int(block), storage, a, a.latency_us * 1e-6)


if __name__ == "__main__":
    main()
