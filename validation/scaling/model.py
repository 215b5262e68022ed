#!/usr/bin/env python3
"""Weak-scaling model of lbm-server's fluid on several GPUs, from its halo bytes and link bandwidths.

Each rank holds a block of B^3 cells (periodic box, blocks as `choose_blocks` cuts them: 2 ranks
1x1x2, 4 ranks 1x2x2, 8 ranks 2x2x2, 16 ranks 2x2x4, 64 ranks 4x4x4). Per step and cut axis the
halo moves 5 populations of 4 bytes per face cell across each of the block's two faces
(lbm-server/src/parallel/halo.rs). Staged through the host, as lbm-server does it, a face goes
device -> host (PCIe), rank -> rank (the link) and host -> device (PCIe), one axis after the other,
each axis paying a fixed latency (a submission, a map and an MPI round). Overlapped, the exchange
hides behind the interior's update where it is shorter (not yet done by lbm-server).

Usage: python3 validation/scaling/model.py [--block 256] [--mlups 18100] [--latency-us 30]
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


def halo_time(block, ranks, stage, link, latency):
    """Seconds per step of the halo exchange of one rank: per cut axis, two faces."""
    face_bytes = 5 * 4 * block * block
    cut = sum(1 for b in BLOCKS[ranks] if b > 1)
    per_axis = 2 * face_bytes / stage + face_bytes / link + 2 * face_bytes / stage if stage else face_bytes / link
    return cut * (per_axis + latency), cut * 2 * face_bytes


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--block", type=int, default=256, help="cells per block edge")
    p.add_argument("--mlups", type=float, default=18100.0, help="one GPU's MLUPS (H200 FP32, BENCHMARKS.md)")
    p.add_argument("--latency-us", type=float, default=30.0, help="fixed cost per cut axis and step [us]")
    a = p.parse_args()
    compute = a.block**3 / (a.mlups * 1e6)
    latency = a.latency_us * 1e-6
    print(f"block {a.block}^3 per GPU, {a.mlups:.0f} MLUPS per GPU: {compute * 1e3:.3f} ms per step")
    print("weak-scaling efficiency (one GPU's time per step / the rank's), staged | overlapped")
    ranks = [2, 4, 8, 16, 64]
    print(f"{'path':48}" + "".join(f"{n:>14}" for n in ranks))
    paths = [(f"{pcie} + {name}", PCIE[pcie], bw) for pcie in PCIE for name, bw in LINKS.items()]
    paths.append(("NVLink 4 device to device (no staging)", None, NVLINK))
    for name, stage, link in paths:
        cells = []
        for n in ranks:
            halo, _ = halo_time(a.block, n, stage, link, latency)
            staged = compute / (compute + halo)
            overlapped = compute / max(compute, halo + latency)
            cells.append(f"{100 * staged:5.0f}% |{100 * overlapped:4.0f}%")
        print(f"{name:48}" + "".join(f"{c:>14}" for c in cells))
    _, sent = halo_time(a.block, 8, None, 1, 0)
    print(f"halo sent per rank and step at 8 ranks (2x2x2): {sent / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
