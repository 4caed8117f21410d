#!/usr/bin/env python3
"""lampshade against Mesa's llvmpipe on the anchor scenes, run interleaved on this machine.

    python3 benches/llvmpipe.py --anchors ../shared/anchors/llvmpipe [--repeats 3] [--frames 10]
                                [--threads 2,1] [--scaling] > report.md

For every anchor scene, shading mode and thread count it runs llvmpipe's own harness (`glref`,
built from the anchor folder's sources into a temporary folder; its Debian packages come from the
anchor folder's `setup.sh`) and `lampshade bench --json` one after the other, `--repeats` times,
so both see the same machine load, and reports the median of the per-run medians, their ratio and
the image difference of our frame against llvmpipe's. With `--scaling` it also measures frame time
against triangle count (10^3 ... 10^7) and resolution (480p ... 4K), and peak memory per triangle.

This is a benchmark: it prints figures and asserts nothing. Absolute times drift between runs on
shared machines (the anchor README measured 1.05-1.4x); the ratios of interleaved runs are what to
compare. Needs a release build: `cargo build --release`.
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

SCENES = [
    # (anchor JSON stem, our scene file)
    ("s1_two_spheres", "scenes/bench/two-spheres.ron"),
    ("s1_two_spheres_800x600", "scenes/bench/two-spheres-800x600.ron"),
    ("s2_dense_sphere", "scenes/bench/dense-sphere.ron"),
    ("s3_overdraw", "scenes/bench/overdraw.ron"),
]
MODES = ["flat", "gouraud", "phong", "blinn"]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAMPSHADE = os.path.join(ROOT, "target", "release", "lampshade")


def build_glref(anchors):
    """Builds llvmpipe's harness in a temporary copy of the anchor folder."""
    work = tempfile.mkdtemp(prefix="glref-")
    for name in ("Makefile", "src", "scenes"):
        source = os.path.join(anchors, name)
        target = os.path.join(work, name)
        (shutil.copytree if os.path.isdir(source) else shutil.copy)(source, target)
    subprocess.run(["make", "-s", "-C", work], check=True)
    return work


def glref_median(work, stem, mode, threads, frames):
    out = os.path.join(work, "frame.png")
    result = os.path.join(work, "result.jsonl")
    if os.path.exists(result):
        os.remove(result)
    env = dict(os.environ, LP_NUM_THREADS=str(threads))
    subprocess.run(
        [os.path.join(work, "glref"), os.path.join(work, "scenes", stem + ".json"), "--mode", mode,
         "--frames", str(frames), "--warmup", "3", "--out", out, "--json", result],
        check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(result) as lines:
        return json.loads(lines.readlines()[-1])["median_ms"]


def lampshade_bench(scene, modes, threads, frames, extra=()):
    command = [LAMPSHADE, "bench", scene, "--json", "--frames", str(frames), "--warmup", "3",
               "--modes", ",".join(modes), "--threads", str(threads), *extra]
    output = subprocess.run(command, check=True, capture_output=True, text=True, cwd=ROOT).stdout
    return [json.loads(line) for line in output.splitlines() if line.startswith("{")]


def compare(args):
    work = build_glref(args.anchors)
    out_dir = os.path.join(args.anchors, "out")
    rows = []
    for stem, scene in SCENES:
        for mode in MODES:
            for threads in args.threads:
                ours, theirs, ours_json = [], [], None
                for _ in range(args.repeats):
                    theirs.append(glref_median(work, stem, mode, threads, args.frames))
                    ours_json = lampshade_bench(scene, [mode], threads, args.frames,
                                                ["--anchors", out_dir])[0]
                    ours.append(ours_json["median_ms"])
                rows.append((stem, ours_json, mode, threads, statistics.median(ours),
                             statistics.median(theirs)))
                print(f"{stem} {mode} {threads}: ours {statistics.median(ours):.1f} ms, "
                      f"llvmpipe {statistics.median(theirs):.1f} ms", file=sys.stderr)
    print("| scene | triangles | mode | threads | lampshade ms | llvmpipe ms | ratio | "
          "mean abs diff | max abs diff | pixels > 2/255 |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for stem, info, mode, threads, ours, theirs in rows:
        print(f"| {stem} | {info['triangles']:,} | {mode} | {threads} | {ours:.1f} | {theirs:.1f} | "
              f"{ours / theirs:.2f} | {info.get('llvmpipe_mean_abs', float('nan')):.3f} | "
              f"{info.get('llvmpipe_max_abs', '?')} | "
              f"{100 * info.get('llvmpipe_share_over_2', float('nan')):.2f}% |")
    shutil.rmtree(work, ignore_errors=True)


def scaling(args):
    folder = tempfile.mkdtemp(prefix="lampshade-scaling-")
    print("\n| triangles | sphere(N) | median ms (phong, 1920×1080) | Mtri/s | peak MiB | bytes per triangle |")
    print("|---:|---:|---:|---:|---:|---:|")
    for target in [10**3, 10**4, 10**5, 10**6, 10**7]:
        n = max(2, round((target / 2) ** 0.5))
        path = os.path.join(folder, f"sphere-{n}.ron")
        with open(path, "w") as scene:
            scene.write(
                "Scene(image: (width: 1920, height: 1080), "
                "camera: Perspective(eye: (1.79, -2.445, 1.206), target: (0, 0, 0), up: (0, 0, 1), fov: 30),"
                " lights: [Directional(direction: (-1, 1, -1))],"
                f" objects: [(mesh: Sphere(segments: {n}), back_faces: Lit)])\n")
        info = lampshade_bench(path, ["phong"], args.threads[0], max(3, args.frames // 3))[0]
        memory = info["peak_memory_mib"]
        print(f"| {info['triangles']:,} | {n} | {info['median_ms']:.1f} | "
              f"{info['triangles_per_s'] / 1e6:.1f} | {memory:.0f} | "
              f"{memory * 2**20 / info['triangles']:.0f} |")
    print("\n| resolution | median ms (two-spheres, phong) | median ms (two-spheres, flat) | Mpix/s (phong) |")
    print("|---|---:|---:|---:|")
    for width, height in [(854, 480), (1280, 720), (1920, 1080), (2560, 1440), (3840, 2160)]:
        infos = lampshade_bench("scenes/bench/two-spheres.ron", ["phong", "flat"], args.threads[0],
                                args.frames, ["--width", str(width), "--height", str(height)])
        phong, flat = infos
        print(f"| {width}×{height} | {phong['median_ms']:.1f} | {flat['median_ms']:.1f} | "
              f"{phong['shaded_pixels_per_s'] / 1e6:.1f} |")
    shutil.rmtree(folder, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--anchors", required=True, help="the llvmpipe anchor folder (shared/anchors/llvmpipe)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--frames", type=int, default=10)
    parser.add_argument("--threads", default="2,1", help="comma-separated thread counts")
    parser.add_argument("--scaling", action="store_true", help="also the triangle-count and resolution sweeps")
    parser.add_argument("--no-compare", action="store_true", help="skip the llvmpipe comparison")
    args = parser.parse_args()
    args.threads = [int(t) for t in args.threads.split(",")]
    args.anchors = os.path.abspath(args.anchors)
    if not os.path.exists(LAMPSHADE):
        sys.exit("build lampshade first: cargo build --release")
    if not args.no_compare:
        compare(args)
    if args.scaling:
        scaling(args)


if __name__ == "__main__":
    main()
