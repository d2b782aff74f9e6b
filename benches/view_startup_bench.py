#!/usr/bin/env python3
"""Start-up and frame time of `billow view --headless`, builds side by side
(docs/performance.md, "Start-up and the volume pass on lavapipe").

Each variant is a billow binary, the folder holding the scene's files for it (`make demo`'s
out/: demo.ron, oak.billow, oak_pruned.billow, oak_cloud.billow, and empty64.billow, a 64³
volume with nothing in it: `billow voxelize MESH -o empty64.billow --res 64 --bounds
1000,1000,1000,1001,1001,1001`) and optional environment settings. The cases run in
rounds; within a round every case runs each variant once, the variants' order rotated
from case to case and round to round, so a change of load falls on all of them. Per case
and variant: the median over rounds of the command's wall time, its first frame and its
best frame (`frame_ms_min`), and of `startup_ms` where the build reports it.

Usage: view_startup_bench.py --variant before=/tmp/billow-old,out \\
                             --variant after=target/release/billow,out [--rounds 3]
                             [--variant 'decoded=/tmp/billow-old,out,BILLOW_VIEW_BC=decode@demo, 3 frames']
A variant's `@CASE` suffix limits it to that case.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

BG = ["--background", "0.55,0.62,0.72"]
CASES = [
    ("empty 64^3 volume at 64x64", ["empty64.billow", "--size", "64x64"]),
    ("oak 128^3 volume at 320x240", ["oak.billow", "--size", "320x240"]),
    ("make demo's picture (640x480, 1 frame)", ["demo.ron", "--size", "640x480"] + BG),
    ("demo, 3 frames", ["demo.ron", "--size", "640x480", "--frames", "3"] + BG),
    ("demo, 3 frames, shadows off",
     ["demo.ron", "--size", "640x480", "--frames", "3", "--shadows", "off"] + BG),
]


def parse_variant(s):
    name, rest = s.split("=", 1)
    only = None
    if "@" in rest:
        rest, only = rest.split("@", 1)
    parts = rest.split(",")
    env = dict(p.split("=", 1) for p in parts[2:])
    return name, (os.path.abspath(parts[0]), os.path.abspath(parts[1]), env, only)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--variant", action="append", required=True)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--jsonl", help="also write every run here")
    a = ap.parse_args()
    variants = dict(parse_variant(v) for v in a.variant)
    names = list(variants)
    rows = []
    log = open(a.jsonl, "w") if a.jsonl else None
    for r in range(a.rounds):
        for ci, (case, args) in enumerate(CASES):
            vs = [v for v in names if variants[v][3] in (None, case)]
            k = (r + ci) % len(vs)
            for v in vs[k:] + vs[:k]:
                binary, folder, env, _ = variants[v]
                shot = os.path.join(folder, f".startup_bench_{ci}_{names.index(v)}.png")
                cmd = [binary, "view", args[0], "--headless", "--screenshot", shot, "--json",
                       "-q"] + args[1:]
                load = os.getloadavg()[0]
                t = time.monotonic()
                p = subprocess.run(cmd, capture_output=True, text=True, cwd=folder,
                                   env=dict(os.environ, NODEVICE_SELECT="1", **env))
                wall = time.monotonic() - t
                if p.returncode != 0:
                    sys.exit(f"view_startup_bench: {v}: {' '.join(cmd)}: {p.stderr.strip()}")
                j = json.loads(p.stdout)
                row = {"round": r, "case": case, "variant": v, "wall_s": wall, "load1": load,
                       "first_ms": j["frame_ms_first"], "min_ms": j["frame_ms_min"],
                       "frames": j["frames"], "startup": j.get("startup_ms")}
                rows.append(row)
                if log:
                    log.write(json.dumps(row) + "\n")
                    log.flush()
        print(f"round {r + 1} of {a.rounds}: done", file=sys.stderr)
    loads = [x["load1"] for x in rows]
    print(f"{a.rounds} rounds; load average (1 min) during the runs {min(loads):.2f}–"
          f"{max(loads):.2f}\n")
    print("| case | variant | wall s | first frame ms | best frame ms | start-up ms "
          "(read / adapter / upload / pipelines / first frame / total) |")
    print("|---|---|---:|---:|---:|---|")
    med = statistics.median
    for case, _ in CASES:
        for v in names:
            xs = [x for x in rows if x["case"] == case and x["variant"] == v]
            if not xs:
                continue
            best = f"{med(x['min_ms'] for x in xs):.0f}" if xs[0]["frames"] > 1 else "–"
            su = "–"
            if xs[0]["startup"]:
                keys = ["read", "adapter", "upload", "pipelines", "first_frame", "total"]
                su = " / ".join(f"{med(x['startup'][k] for x in xs):.0f}" for k in keys)
            print(f"| {case} | {v} | {med(x['wall_s'] for x in xs):.2f} | "
                  f"{med(x['first_ms'] for x in xs):.0f} | {best} | {su} |")


if __name__ == "__main__":
    main()
