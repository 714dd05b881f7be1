#!/usr/bin/env python3
"""Overhead of splitting a render into parts (issue 25's benchmark target: under 5% for N = 8 on
the Cornell box at 1024 spp).

One process renders the scene (`pt render --spp S`); then N processes render the N parts one
after another on the same machine, each with every core (`pt render --part K/N`), and `pt merge`
combines them. The overhead is (parts + merge) / one process - 1, wall-clock, the pairs taken in
turn so that drift of the machine's speed falls on both. Each round also checks the merged image
equals the one-process image bit for bit (`pt compare --identical`).

Usage: python3 references/bench_split.py [--pt target/release/pt] [--parts 8] [--spp 1024]
       [--rounds 3] [--scene SCENE]    (no scene: the built-in Cornell box)
Prints one line per round and the median overhead; nothing is written to the repository.
"""

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def timed(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pt", default=str(REPO / "target" / "release" / "pt"))
    ap.add_argument("--parts", type=int, default=8)
    ap.add_argument("--spp", type=int, default=1024)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--scene", default=None)
    a = ap.parse_args()
    if not Path(a.pt).exists():
        sys.exit(f"{a.pt} not found: run `cargo build --release` first")
    scene = [a.scene] if a.scene else []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        whole = tmp / "whole.exr"
        base = [a.pt, "render", *scene, "--spp", str(a.spp), "--quiet"]
        # Warm-up (page cache, CPU frequency).
        timed(base + ["-o", str(whole)])
        ratios = []
        for r in range(a.rounds):
            t_whole = timed(base + ["-o", str(whole)])
            parts = [tmp / f"p{k}.ptpart" for k in range(1, a.parts + 1)]
            for p in parts:
                p.unlink(missing_ok=True)
            t_parts = sum(
                timed(base + ["--part", f"{k}/{a.parts}", "-o", str(p)])
                for k, p in enumerate(parts, 1))
            merged = tmp / "merged.exr"
            t_merge = timed([a.pt, "merge", *map(str, parts), "-o", str(merged), "--quiet"])
            same = subprocess.run([a.pt, "compare", "--identical", str(merged), str(whole)],
                                  stdout=subprocess.DEVNULL).returncode == 0
            ratio = (t_parts + t_merge) / t_whole
            ratios.append(ratio)
            print(f"round {r + 1}: one process {t_whole:.2f} s, {a.parts} parts {t_parts:.2f} s "
                  f"+ merge {t_merge:.2f} s = {ratio:.4f}x; merged {'==' if same else '!='} one "
                  f"process", flush=True)
            if not same:
                sys.exit("the merged image differs from the one-process render")
        print(f"median overhead of {a.parts} parts: {100 * (statistics.median(ratios) - 1):+.1f}% "
              f"({a.rounds} rounds, {a.spp} spp)")


if __name__ == "__main__":
    main()
