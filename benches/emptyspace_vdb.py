#!/usr/bin/env python3
"""What `billow emptyspace` saves on default `billow voxelize` outputs, and what OpenVDB /
NanoVDB would store for the same occupancy (docs/emptyspace.md, "Against OpenVDB and
NanoVDB").

Usage: emptyspace_vdb.py --billow BIN --out DIR [--vdb] NAME=MESH@RES ...

For each NAME=MESH@RES: `billow voxelize MESH -o DIR/NAME.billow --res RES` (default
options otherwise: BC7 blocks), `billow emptyspace` at default settings (--json: file and
GPU texture bytes before and after, voxels drawn), then, from the same bake with
`--compress none` (the same texels before compression; empty texels stay exactly empty
through BC7, SPEC §12.3), the occupancy of every MIP level: non-empty texels (any byte
non-zero), the 8³ leaves, 16³ lower and 32³ upper internal nodes that hold them. From
those counts:

- NanoVDB (nanovdb/NanoVDB.h, a 4-byte value such as float or Rgba8): leaf 2,144 bytes
  (coordinate, bbox, flags, 64-byte value mask, 4 statistics, 512 values), lower internal
  node 33,856 bytes (bbox, flags, two 512-byte masks, statistics, 4,096 8-byte tiles),
  upper internal node 270,400 bytes (two 4,096-byte masks, 32,768 8-byte tiles), plus the
  grid, tree and root headers (~800 bytes) and 32 bytes per root tile;
- OpenVDB, measured when --vdb is given and pyopenvdb imports: `FloatGrid.memUsage()` of a
  grid whose active voxels are the non-empty texels (one 4-byte channel, the bytes per
  texel of billow's RGBA8).

A VDB holds one resolution, so the "all levels" columns count one grid per MIP level.
Prints a Markdown table on stdout.
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "spec_reader"))
import read_billow  # noqa: E402

LEAF, LOWER, UPPER, HEADERS, ROOT_TILE = 2144, 33856, 270400, 800, 32


def levels(path):
    data = open(path, "rb").read()
    _, _, _, chunks = read_billow.read_container(data)
    header = read_billow.check_header(chunks[0]["payload"].decode("utf-8"))
    dims = header["volume"]["dims"]
    out = []
    vlev = [c for c in chunks if c["tag"] == b"VLEV"]
    for i, ch in enumerate(vlev):
        d = read_billow.mip_dims(dims, i)
        a = np.frombuffer(ch["payload"], dtype=np.uint32).reshape(d[2], d[1], d[0])
        out.append(a != 0)  # z, y, x
    return dims, out


def nodes(mask, log2):
    """Number of (2^log2)³ nodes holding a set voxel."""
    s = 1 << log2
    z, y, x = np.nonzero(mask)
    if len(x) == 0:
        return 0
    key = ((z >> log2).astype(np.int64) << 40) | ((y >> log2).astype(np.int64) << 20) | (x >> log2)
    return len(np.unique(key)) if s else 0


def nanovdb_bytes(mask):
    if not mask.any():
        return HEADERS, 0
    leaves, lower, upper = nodes(mask, 3), nodes(mask, 7), nodes(mask, 12)
    return leaves * LEAF + lower * LOWER + upper * (UPPER + ROOT_TILE) + HEADERS, leaves


def openvdb_bytes(mask):
    import pyopenvdb as vdb

    g = vdb.FloatGrid()
    # copyFromArray takes x, y, z order; only non-zero values become active.
    g.copyFromArray(np.ascontiguousarray(mask.transpose(2, 1, 0)).astype(np.float32))
    return g.memUsage()


def mib(b):
    return "%.2f" % (b / 2**20)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--billow", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--vdb", action="store_true")
    ap.add_argument("cases", nargs="+")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for case in a.cases:
        name, rest = case.split("=", 1)
        mesh, res = rest.rsplit("@", 1)
        src = os.path.join(a.out, name + ".billow")
        pruned = os.path.join(a.out, name + "_pruned.billow")
        raw = os.path.join(a.out, name + "_raw.billow")
        subprocess.run([a.billow, "voxelize", mesh, "-o", src, "--res", res, "-q"], check=True)
        subprocess.run([a.billow, "voxelize", mesh, "-o", raw, "--res", res, "-q",
                        "--compress", "none"], check=True)
        r = subprocess.run([a.billow, "emptyspace", src, "-o", pruned, "--json"], check=True,
                           capture_output=True, text=True)
        s = json.loads(r.stdout)
        dims, lv = levels(raw)
        nano0, leaves0 = nanovdb_bytes(lv[0])
        nano_all = sum(nanovdb_bytes(m)[0] for m in lv)
        row = {
            "name": name, "res": res, "dims": "×".join(map(str, dims)),
            "voxels": int(lv[0].sum()), "fill": lv[0].mean(), "leaves": leaves0,
            "before": s["texel_bytes_before"], "after": s["texel_bytes_after"],
            "saving": s["saving"], "bands": len(s["bands"]), "warning": r.stderr.strip(),
            "file0": s["file_bytes_before"], "file1": s["file_bytes_after"],
            "gpu0": s["gpu_bytes_before"], "gpu1": s["gpu_bytes_after"],
            "drawn": s["voxels_kept"] / max(1, s["voxels_before"]),
            "level0_dense": 4 * lv[0].size, "nano0": nano0, "nano_all": nano_all,
        }
        if a.vdb:
            row["vdb0"] = openvdb_bytes(lv[0])
            row["vdb_all"] = sum(openvdb_bytes(m) for m in lv)
        rows.append(row)
        print(json.dumps(row), file=sys.stderr)
    print("| volume | grid | non-empty voxels (level 0) | 8³ leaves | RGBA8 texels, all levels MiB |"
          " BC7 GPU textures MiB: volume → pruned | BC7 file MiB: volume → pruned |"
          " voxels drawn | NanoVDB level 0 MiB | NanoVDB all levels MiB |"
          + (" OpenVDB level 0 MiB | OpenVDB all levels MiB |" if a.vdb else ""))
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|" if a.vdb else ""))
    for r in rows:
        line = "| %s %s³ | %s | %s (%.1f %%) | %s | %s | %s → %s (**%+.0f %%**) | %s → %s (%+.0f %%) | %.0f %% | %s | %s |" % (
            r["name"], r["res"], r["dims"], f"{r['voxels']:,}", 100 * r["fill"],
            f"{r['leaves']:,}", mib(r["before"]), mib(r["gpu0"]), mib(r["gpu1"]),
            100 * (r["gpu1"] / r["gpu0"] - 1), mib(r["file0"]), mib(r["file1"]),
            100 * (r["file1"] / r["file0"] - 1), 100 * r["drawn"],
            mib(r["nano0"]), mib(r["nano_all"]))
        if a.vdb:
            line += " %s | %s |" % (mib(r["vdb0"]), mib(r["vdb_all"]))
        print(line)


if __name__ == "__main__":
    main()
