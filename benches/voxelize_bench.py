#!/usr/bin/env python3
"""`billow voxelize` against the six-direction raster floor, side by side (see `make bench`).

For every resolution, runs `raster_floor MESH R` and `billow voxelize MESH --res R --json`
alternately (so both see the same machine load), RUNS times each, and writes the medians
(whole-process wall seconds, billow's per-stage seconds and peak memory) to a Markdown file.
Only the Python standard library is used.
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time


def run_rusage(cmd):
    """Like `run`, with the child's own peak RSS from wait4."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = p.stdout.read()
    err = p.stderr.read()
    _, status, ru = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{err.decode(errors='replace')}")
    return wall, ru.ru_maxrss * 1024, ru.ru_utime + ru.ru_stime, out.decode()


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--billow", required=True)
    ap.add_argument("--floor", required=True, help="the compiled raster_floor")
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--res", default="128 256 512")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--extra", default="", help="extra billow arguments (e.g. '--supersample 1')")
    ap.add_argument("--work", default=None, help="folder for the temporary assets (default: next to the mesh)")
    ap.add_argument("--out", required=True, help="Markdown file to write")
    ap.add_argument("--command", default="make bench", help="the command that regenerates the file")
    ap.add_argument("--notes", default=None, help="Markdown appended after the tables")
    ap.add_argument("--sweep-res", type=int, default=256,
                    help="resolution of the supersampling sweep (0: no sweep)")
    ap.add_argument("--sweep", default="1 2 3 4",
                    help="supersampling factors of the sweep (what the coverage samples cost)")
    ap.add_argument("--foliage", default=None,
                    help="a foliage glTF with an OBJ copy beside it (same name, .obj): one more row "
                         "at the sweep resolution, billow on the glTF, the floor on the OBJ")
    a = ap.parse_args()
    work = a.work or os.path.dirname(os.path.abspath(a.mesh))
    asset = os.path.join(work, "bench_tmp.billow")
    extra = a.extra.split()
    stages = ["import", "rasterize", "bake", "mip", "combine", "quantize", "write", "total"]
    load_before = os.getloadavg()
    def measure(r, more, mesh=None, floor_mesh=None):
        """Medians of RUNS alternating floor / billow runs at resolution `r`."""
        mesh, floor_mesh = mesh or a.mesh, floor_mesh or mesh or a.mesh
        floor_s, floor_cpu, floor_rss, b_s, b_cpu, b_rss, b_peak, b_stage = [], [], [], [], [], [], [], {}
        info = None
        for i in range(a.runs):
            w, rss, cpu, _ = run_rusage([a.floor, floor_mesh, str(r)])
            floor_s.append(w), floor_cpu.append(cpu), floor_rss.append(rss)
            cmd = [a.billow, "voxelize", mesh, "-o", asset, "--res", str(r), "--json", *extra, *more]
            w, rss, cpu, out = run_rusage(cmd)
            j = json.loads(out)
            info = j
            b_s.append(w), b_cpu.append(cpu), b_rss.append(rss)
            if j.get("peak_memory_bytes") is not None:
                b_peak.append(j["peak_memory_bytes"])
            for k in stages:
                if k in j["seconds"]:
                    b_stage.setdefault(k, []).append(j["seconds"][k])
            os.remove(asset)
            print(f"res {r} {' '.join(more)} run {i + 1}/{a.runs}: floor {floor_s[-1]:.2f} s, "
                  f"billow {b_s[-1]:.2f} s (load {os.getloadavg()[0]:.2f})", file=sys.stderr)
        return info, dict(res=r, dims=info["dims"], floor=med(floor_s), floor_cpu=med(floor_cpu),
                          floor_rss=med(floor_rss), billow=med(b_s), billow_cpu=med(b_cpu),
                          billow_rss=max(b_rss), peak=max(b_peak) if b_peak else None,
                          stages={k: med(v) for k, v in b_stage.items()},
                          fragments=info["fragments"], voxels=info["non_empty_voxels"],
                          supersample=info["supersample"], triangles=info["triangles"])

    rows = []
    for r in [int(x) for x in a.res.split()]:
        info, row = measure(r, [])
        rows.append(row)
    sweep = [measure(a.sweep_res, ["--supersample", k])[1] for k in a.sweep.split()] if a.sweep_res else []
    foliage = None
    if a.foliage:
        # raster_floor reads `f a/b c/d e/f` faces only: a copy of the OBJ without the
        # normal indices (same vertices, texture coordinates and triangles).
        src = os.path.splitext(a.foliage)[0] + ".obj"
        floor_obj = os.path.join(work, "bench_foliage_v_vt.obj")
        with open(src) as f, open(floor_obj, "w") as o:
            for line in f:
                if line.startswith("f "):
                    line = "f " + " ".join("/".join(v.split("/")[:2]) for v in line.split()[1:]) + "\n"
                o.write(line)
        foliage = measure(a.sweep_res or 256, [], a.foliage, floor_obj)[1]
        os.remove(floor_obj)
    load_after = os.getloadavg()

    gib = lambda b: f"{b / 2**30:.2f} GiB" if b is not None else "—"

    def against_floor(x):
        """The cells `floor s | billow s | ratio | rasterize s | fragments | voxels |`."""
        return (f"{x['floor']:.2f} | {x['billow']:.2f} | **{x['billow'] / x['floor']:.1f}×** "
                f"| {x['stages'].get('rasterize', float('nan')):.2f} | {x['fragments']:,} | {x['voxels']:,} |")
    lines = [
        "# Benchmarks: `billow voxelize` vs. the raster floor",
        "",
        f"Regenerate with `{a.command}` (writes this file). Input: the 200,000-triangle synthetic tree",
        "from `../shared/bench/gen_tree.py`; `raster_floor` is `../shared/bench/raster_floor.c`",
        "built with `cc -O3 -march=native` (one core, one sample per voxel column, nearest texel,",
        "no compositing/MIP/combine/write). `billow voxelize MESH -o OUT --res R --json"
        + (f" {a.extra}" if a.extra else "") + "` (release build,",
        f"defaults otherwise: supersample {info['supersample']}, combine `{info['combine']}`, full MIP chain).",
        "Both programs run alternately, "
        f"{a.runs} times each per resolution; the table shows **medians** of whole-process wall time.",
        "",
        f"- Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, {platform.system()} {platform.release()};"
        f" measured {time.strftime('%Y-%m-%d %H:%M %Z')}.",
        f"- Load average (1/5/15 min) before: {load_before[0]:.2f}/{load_before[1]:.2f}/{load_before[2]:.2f},"
        f" after: {load_after[0]:.2f}/{load_after[1]:.2f}/{load_after[2]:.2f}"
        " (the machine is shared: other jobs compete for the cores, so absolute times are noisy;"
        " the ratio is the figure to compare).",
        "",
        "| res | dims | raster_floor s | billow s | ratio (target ≤ 2) | billow CPU s | floor CPU s "
        "| billow peak memory | floor peak RSS |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for x in rows:
        d = "×".join(str(v) for v in x["dims"])
        lines.append(f"| {x['res']} | {d} | {x['floor']:.2f} | {x['billow']:.2f} | **{x['billow'] / x['floor']:.1f}×** "
                     f"| {x['billow_cpu']:.2f} | {x['floor_cpu']:.2f} | {gib(x['peak'] or x['billow_rss'])} "
                     f"| {gib(x['floor_rss'])} |")
    lines += ["", "Per-stage seconds of `billow voxelize` (medians, from `--json`; `total` is the",
              "process's own measure, without process start and exit):", "",
              "| res | " + " | ".join(k for k in stages if k in rows[0]["stages"]) + " | fragments | non-empty voxels |",
              "|---|" + "---|" * (len([k for k in stages if k in rows[0]["stages"]]) + 2)]
    for x in rows:
        lines.append(f"| {x['res']} | " + " | ".join(f"{x['stages'][k]:.2f}" for k in stages if k in x["stages"])
                     + f" | {x['fragments']:,} | {x['voxels']:,} |")
    lines.append("")
    if sweep:
        lines += [f"What the coverage samples cost at {a.sweep_res}³ (`--supersample K`: K×K samples per",
                  "voxel column, the default 4; same alternating runs; what they buy in accuracy is the",
                  "supersampling sweep of [accuracy.md](accuracy.md)):", "",
                  "| K | raster_floor s | billow s | ratio | rasterize s | fragments | non-empty voxels |",
                  "|---|---|---|---|---|---|---|"]
        for x in sweep:
            lines.append(f"| {x['supersample']} | {against_floor(x)}")
        lines.append("")
    # The budget: what the target leaves once everything but rasterizing is paid for.
    for x in rows:
        if x["res"] == (a.sweep_res or 256):
            rest = sum(v for k, v in x["stages"].items() if k not in ("rasterize", "total"))
            budget = 2 * x["floor"]
            lines += [f"**The budget at {x['res']}³:** the target allows {budget:.2f} s (2 × the floor). "
                      f"billow's stages other than rasterizing (import, bake, MIP, combine, quantize, write) take "
                      f"{rest:.2f} s, {100 * rest / budget:.0f} % of that budget, before a single fragment is made; "
                      f"rasterizing takes {x['stages'].get('rasterize', float('nan')):.2f} s.", ""]
    if foliage:
        x = foliage
        d = "×".join(str(v) for v in x["dims"])
        lines += [f"Foliage, the main use case: `{a.foliage}` ({x['triangles']:,} triangles) at the "
                  "sweep resolution; billow reads the glTF, the floor the OBJ copy of the same mesh (with its "
                  "own opaque test texture, so its alpha test never discards):", "",
                  "| mesh | dims | raster_floor s | billow s | ratio | rasterize s | fragments | non-empty voxels |",
                  "|---|---|---|---|---|---|---|---|",
                  f"| {os.path.splitext(os.path.basename(a.foliage))[0]} | {d} | {against_floor(x)}", ""]
    if a.notes:
        with open(a.notes) as f:
            lines.append(f.read().rstrip())
    text = "\n".join(lines) + "\n"
    with open(a.out, "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
