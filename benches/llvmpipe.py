#!/usr/bin/env python3
"""lampshade against Mesa's llvmpipe on the anchor scenes, run interleaved on this machine.

    python3 benches/llvmpipe.py --anchors ../shared/anchors/llvmpipe [--repeats 3] [--frames 10]
                                [--threads 2,1] [--scenes PATTERNS] [--scaling] > report.md

For every anchor scene, shading mode and thread count it runs llvmpipe's own harness (`glref`,
built from the anchor folder's sources into a temporary folder; its Debian packages come from the
anchor folder's `setup.sh`) and `lampshade bench --json` one after the other, `--repeats` times,
so both see the same machine load, and reports the median of the per-run medians, their ratio and
the image difference of our frame against llvmpipe's. With `--scaling` it also measures frame time
against triangle count (10^3 ... 10^7) and resolution (480p ... 4K), and peak memory per triangle.

The feature scenes (S1 with one feature: a spot light, 4x MSAA, a shadow map, a texture, a ground
plane; the anchor's FEATURES.md; a point light and two OpenGL-table materials whose shininess is
not a whole number, whose scenes for llvmpipe are ours, in benches/anchors/; and, for lampshade
alone, Slerp and Cook-Torrance, which llvmpipe's harness cannot express) get a table of their own with each one's cost over plain S1 in the same run
("x plain S1"), for both renderers: for every mode, thread count and repeat, plain S1 runs
(both renderers) before and after the feature scenes of that mode, and each feature's ratio is its
frame over the mean of those two S1 frames; the table gives the medians over the repeats. The
scenes with the ground plane also get their ratio to `s1_ground` of the same repeat ("x ground"):
the same geometry and pixels, so that is the cost of the spot light or the shadow map alone.
llvmpipe has no shadows in flat and gouraud, so the shadow scenes run in phong and blinn only.
The real-mesh scenes (`s4_*`: the koala and nefertiti scans, Keenan Crane's cow Spot, the glTF Duck
and nefertiti refined to a million triangles; their anchor JSON is in benches/anchors/, written with
the scenes by benches/anchors/gen_real_mesh_scenes.py) get a table with our stage times and
llvmpipe's frames compared with ours, and a table of our load times; the meshes that are generated
rather than committed are written by benches/gen_meshes.py first when missing.
`--scenes` selects rows by anchor name (comma-separated shell patterns; `features` stands for every
feature scene, `meshes` for every real-mesh scene), e.g. `--scenes features` or
`--scenes s1_two_spheres,s1_spot` or `--scenes meshes`.

This is a benchmark: it prints figures and asserts nothing. Absolute times drift between runs on
shared machines (the anchor README measured 1.05-1.4x); the ratios of interleaved runs are what to
compare. Builds the release binary first (`cargo build --release`, nothing when it is current),
so that a stale build is never measured; `LAMPSHADE=path` measures that binary instead, as is.
"""

import argparse
import collections
import fnmatch
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
SHADED = ["phong", "blinn"]
# S1 with one feature each. `stem`: the row's name, and the JSON scene's for llvmpipe; `scene`: ours;
# `modes`: the rows' modes; `base`: the scene it adds one feature to when that is not plain S1;
# `llvmpipe`: where llvmpipe's scene is: "anchor" (the anchor's scenes/, its frames in out/features/,
# FEATURES.md), a JSON file of ours (its frames are kept from the run), or None (lampshade alone);
# `ours_mode`: the `lampshade bench` mode when it is not the row's ("scene": the scene's own shading
# and lighting model, which the other modes would replace).
Feature = collections.namedtuple("Feature", "stem scene modes base llvmpipe ours_mode")
FEATURE_SCENES = [
    Feature("s1_spot", "scenes/bench/spot.ron", MODES, None, "anchor", None),
    Feature("s1_spot_ground", "scenes/bench/spot-ground.ron", MODES, "s1_ground", "anchor", None),
    Feature("s1_point", "scenes/bench/point.ron", MODES, None, "benches/anchors/s1_point.json", None),
    Feature("s1_materials", "scenes/bench/materials.ron", MODES, None, "benches/anchors/s1_materials.json", None),
    Feature("s1_msaa4", "scenes/bench/msaa4.ron", MODES, None, "anchor", None),
    Feature("s1_ground", "scenes/bench/ground.ron", MODES, None, "anchor", None),
    Feature("s1_shadow", "scenes/bench/shadow.ron", SHADED, "s1_ground", "anchor", None),
    Feature("s1_shadow2", "scenes/bench/shadow2.ron", SHADED, "s1_ground", "anchor", None),
    Feature("s1_shadow_noplane", "scenes/bench/shadow-noplane.ron", SHADED, None, "anchor", None),
    Feature("s1_textured", "scenes/bench/textured.ron", MODES, None, "anchor", None),
    Feature("s1_studio", "scenes/bench/studio.ron", SHADED, "s1_ground", "benches/anchors/s1_studio.json", None),
    Feature("s1_slerp", "scenes/bench/slerp.ron", SHADED, None, None, None),
    Feature("s1_textured_slerp", "scenes/bench/textured-slerp.ron", SHADED, None, None, None),
    Feature("s1_cook_torrance", "scenes/bench/cook-torrance.ron", ["phong"], None, None, "scene"),
]
PLAIN_S1 = ("s1_two_spheres", "scenes/bench/two-spheres.ron")
# Real meshes (anchor JSON stem in benches/anchors/, our scene file): scans, Spot, the glTF Duck and
# nefertiti refined to a million triangles, written by benches/anchors/gen_real_mesh_scenes.py.
# cow-textured is cow with its texture, which glref cannot put on an OBJ: it is timed against
# llvmpipe's untextured cow.
MESH_SCENES = [
    ("s4_koala", "scenes/bench/koala.ron"),
    ("s4_koala_far", "scenes/bench/koala-far.ron"),
    ("s4_nefertiti", "scenes/bench/nefertiti.ron"),
    ("s4_cow", "scenes/bench/cow.ron"),
    ("s4_cow_close", "scenes/bench/cow-close.ron"),
    ("s4_cow", "scenes/bench/cow-textured.ron"),
    ("s4_duck", "scenes/bench/duck.ron"),
    ("s4_nefertiti_1m", "benches/scenes/nefertiti-1m.ron"),
]
# The meshes benches/gen_meshes.py writes (not committed).
GENERATED_MESHES = ["benches/meshes/nefertiti-1m.obj", "benches/meshes/duck.obj"]
# CPU used by other processes during each llvmpipe run's timed frames (glref's `foreign_cores`).
FOREIGN_CORES = []
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# `LAMPSHADE=path` measures another binary (a copy, so that a rebuild cannot swap it mid-run).
LAMPSHADE = os.environ.get("LAMPSHADE", os.path.join(ROOT, "target", "release", "lampshade"))


def build_glref(anchors):
    """Builds llvmpipe's harness in a temporary copy of the anchor folder, with our own JSON scenes
    beside the anchor's, and a folder for the frames of ours (`OWN_FRAMES`)."""
    work = tempfile.mkdtemp(prefix="glref-")
    for name in ("Makefile", "src", "scenes"):
        source = os.path.join(anchors, name)
        target = os.path.join(work, name)
        (shutil.copytree if os.path.isdir(source) else shutil.copy)(source, target)
    for feature in FEATURE_SCENES:
        if feature.llvmpipe not in ("anchor", None):
            shutil.copy(os.path.join(ROOT, feature.llvmpipe), os.path.join(work, "scenes", feature.stem + ".json"))
    os.mkdir(os.path.join(work, OWN_FRAMES))
    subprocess.run(["make", "-s", "-C", work], check=True)
    return work


# In the harness's folder: llvmpipe's last frame of each of our own JSON scenes and mode, named as
# the anchor's out/features/ names them, for `lampshade bench --anchors`.
OWN_FRAMES = "own-frames"


def glref_median(work, scene, mode, threads, frames, out=None):
    """llvmpipe's median frame of `scene` (an anchor stem in the anchor folder's scenes/, or a
    path to a JSON file), writing its last frame to `out` and to `OWN_FRAMES`."""
    out = out or os.path.join(work, "frame.png")
    result = os.path.join(work, "result.jsonl")
    if os.path.exists(result):
        os.remove(result)
    env = dict(os.environ, LP_NUM_THREADS=str(threads))
    path = scene if scene.endswith(".json") else os.path.join(work, "scenes", scene + ".json")
    subprocess.run(
        [os.path.join(work, "glref"), path, "--mode", mode,
         "--frames", str(frames), "--warmup", "3", "--out", out, "--json", result],
        check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(result) as lines:
        line = json.loads(lines.readlines()[-1])
    FOREIGN_CORES.append(line.get("foreign_cores", float("nan")))
    stem = os.path.splitext(os.path.basename(scene))[0]
    shutil.copy(out, os.path.join(work, OWN_FRAMES, f"{stem}__{mode}.png"))
    return line["median_ms"]


def lampshade_bench(scene, modes, threads, frames, extra=()):
    command = [LAMPSHADE, "bench", scene, "--json", "--frames", str(frames), "--warmup", "3", "--loads", "0",
               "--modes", ",".join(modes), "--threads", str(threads), *extra]
    output = subprocess.run(command, check=True, capture_output=True, text=True, cwd=ROOT).stdout
    return [json.loads(line) for line in output.splitlines() if line.startswith("{")]


def selected(stem, patterns):
    return patterns is None or any(
        (pattern == "features" and stem in {f.stem for f in FEATURE_SCENES})
        or (pattern == "meshes" and stem in {m[0] for m in MESH_SCENES})
        or fnmatch.fnmatch(stem, pattern)
        for pattern in patterns)


def compare(args, work):
    out_dir = os.path.join(args.anchors, "out")
    rows = []
    for stem, scene in SCENES:
        if not selected(stem, args.scenes):
            continue
        for mode in args.modes:
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
    if not rows:
        return
    print("| scene | triangles | mode | threads | lampshade ms | llvmpipe ms | ratio | "
          "mean abs diff | max abs diff | pixels > 2/255 |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for stem, info, mode, threads, ours, theirs in rows:
        print(f"| {stem} | {info['triangles']:,} | {mode} | {threads} | {ours:.1f} | {theirs:.1f} | "
              f"{ours / theirs:.2f} | {image_columns(info)} |")


def image_columns(info):
    return (f"{info.get('llvmpipe_mean_abs', float('nan')):.3f} | {info.get('llvmpipe_max_abs', '?')} | "
            f"{100 * info.get('llvmpipe_share_over_2', float('nan')):.2f}%")


def compare_features(args, work):
    """The feature scenes, each mode's group bracketed by plain S1 runs (module documentation)."""
    anchor_frames = os.path.join(args.anchors, "out", "features")
    features = [f for f in FEATURE_SCENES if selected(f.stem, args.scenes)]
    if not features:
        return
    # (stem, mode, threads) -> {"ours": [ms], "theirs": [ms], "ours_x": [ratio], "theirs_x": [ratio],
    #                           "ours_base": [ratio], "theirs_base": [ratio], "info": json}
    results = {}
    bases = {f.stem: f.base for f in features}
    load_before = os.getloadavg()[0]
    del FOREIGN_CORES[:]

    def row_of(key, info):
        return results.setdefault(key, {"ours": [], "theirs": [], "ours_x": [], "theirs_x": [],
                                        "ours_base": [], "theirs_base": [], "info": info})

    def pair(feature, mode, threads):
        """(our median, llvmpipe's or None, our JSON line) of one run of each."""
        theirs = None
        if feature.llvmpipe is not None:
            theirs = glref_median(work, feature.stem, mode, threads, args.frames)
        frames = anchor_frames if feature.llvmpipe == "anchor" else os.path.join(work, OWN_FRAMES)
        info = lampshade_bench(feature.scene, [feature.ours_mode or mode], threads, args.frames,
                               ["--anchors", frames])[0]
        return info["median_ms"], theirs, info

    plain = Feature(*PLAIN_S1, MODES, None, "anchor", None)
    for mode in MODES:
        group = [f for f in features if mode in f.modes]
        if not group:
            continue
        for threads in args.threads:
            for _ in range(args.repeats):
                before = pair(plain, mode, threads)
                measured = {f.stem: pair(f, mode, threads) for f in group}
                after = pair(plain, mode, threads)
                ours_s1 = (before[0] + after[0]) / 2
                theirs_s1 = (before[1] + after[1]) / 2
                row = row_of((PLAIN_S1[0], mode, threads), before[2])
                row["ours"] += [before[0], after[0]]
                row["theirs"] += [before[1], after[1]]
                for stem, (ours, theirs, info) in measured.items():
                    row = row_of((stem, mode, threads), info)
                    row["ours"].append(ours)
                    row["ours_x"].append(ours / ours_s1)
                    if theirs is not None:
                        row["theirs"].append(theirs)
                        row["theirs_x"].append(theirs / theirs_s1)
                    if bases[stem] in measured:
                        row["ours_base"].append(ours / measured[bases[stem]][0])
                        if theirs is not None:
                            row["theirs_base"].append(theirs / measured[bases[stem]][1])
                    llvmpipe = (f"llvmpipe {theirs:.1f} ms (x{theirs / theirs_s1:.2f} S1)" if theirs is not None
                                else "no llvmpipe scene")
                    print(f"{stem} {mode} {threads}: ours {ours:.1f} ms (x{ours / ours_s1:.2f} S1), {llvmpipe}",
                          file=sys.stderr)
    print("\n| scene | triangles | mode | threads | lampshade ms | llvmpipe ms | ratio | lampshade × plain S1 | "
          "llvmpipe × plain S1 | lampshade × ground | llvmpipe × ground | mean abs diff | max abs diff | "
          "pixels > 2/255 |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")

    def ratio(values, empty):
        return f"{statistics.median(values):.2f}" if values else empty
    for stem in [PLAIN_S1[0]] + [f.stem for f in features]:
        for mode in MODES:
            for threads in args.threads:
                row = results.get((stem, mode, threads))
                if row is None:
                    continue
                ours = statistics.median(row["ours"])
                if row["theirs"]:
                    theirs = statistics.median(row["theirs"])
                    llvmpipe = f"{theirs:.1f} | {ours / theirs:.2f}"
                    images = image_columns(row["info"])
                else:
                    llvmpipe, images = "– | –", "– | – | –"
                print(f"| {stem} | {row['info']['triangles']:,} | {mode} | {threads} | {ours:.1f} | {llvmpipe} | "
                      f"{ratio(row['ours_x'], '1')} | {ratio(row['theirs_x'], '–' if not row['theirs'] else '1')} | "
                      f"{ratio(row['ours_base'], '–')} | {ratio(row['theirs_base'], '–')} | {images} |")
    print(f"\nLoad average (1 min) {load_before:.2f} before the feature runs, {os.getloadavg()[0]:.2f} after; "
          f"other processes used a median of {statistics.median(FOREIGN_CORES):.2f} cores "
          f"(max {max(FOREIGN_CORES):.2f}) during llvmpipe's timed frames ({len(FOREIGN_CORES)} runs).")


def compare_meshes(args, work):
    """The real-mesh scenes: both renderers interleaved as in `compare`, llvmpipe's frames saved
    for the image columns, our stage times, and our load time (median of 5 loads, MB/s)."""
    meshes = [m for m in MESH_SCENES if selected(m[0], args.scenes)]
    if not meshes:
        return
    if any(not os.path.exists(os.path.join(ROOT, mesh)) for mesh in GENERATED_MESHES):
        subprocess.run([sys.executable, os.path.join(ROOT, "benches", "gen_meshes.py")], check=True)
    frames = os.path.join(work, "mesh-frames")
    os.makedirs(frames, exist_ok=True)
    load_before = os.getloadavg()[0]
    del FOREIGN_CORES[:]
    rows = []
    for stem, scene in meshes:
        anchor = os.path.join(ROOT, "benches", "anchors", stem + ".json")
        for mode in args.modes:
            for threads in args.threads:
                ours, theirs, info = [], [], None
                for _ in range(args.repeats):
                    out = os.path.join(frames, f"{stem}__{mode}.png")
                    theirs.append(glref_median(work, anchor, mode, threads, args.frames, out))
                    info = lampshade_bench(scene, [mode], threads, args.frames, ["--anchors", frames])[0]
                    ours.append(info["median_ms"])
                rows.append((scene, info, mode, threads, statistics.median(ours), statistics.median(theirs)))
                print(f"{scene} {mode} {threads}: ours {statistics.median(ours):.1f} ms, "
                      f"llvmpipe {statistics.median(theirs):.1f} ms", file=sys.stderr)
    print("\n| scene | triangles | mode | threads | lampshade ms | llvmpipe ms | ratio | geometry ms | raster ms* | "
          "shade ms* | cores | mean abs diff | max abs diff | pixels > 2/255 |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for scene, info, mode, threads, ours, theirs in rows:
        name = os.path.splitext(os.path.basename(scene))[0]
        print(f"| {name} | {info['triangles']:,} | {mode} | {threads} | {ours:.1f} | {theirs:.1f} | "
              f"{ours / theirs:.2f} | {info['geometry_ms']:.1f} | {info['raster_thread_ms']:.1f} | "
              f"{info['shade_thread_ms']:.1f} | {info.get('cores_busy') or float('nan'):.2f} | {image_columns(info)} |")
    print(f"\nLoad average (1 min) {load_before:.2f} before the runs, {os.getloadavg()[0]:.2f} after; "
          f"other processes used a median of {statistics.median(FOREIGN_CORES):.2f} cores "
          f"(max {max(FOREIGN_CORES):.2f}) during llvmpipe's timed frames ({len(FOREIGN_CORES)} runs).")
    print("\n| scene | bytes read | threads | load ms (median of 5) | MB/s |")
    print("|---|---:|---:|---:|---:|")
    for _, scene in meshes:
        for threads in args.threads:
            command = [LAMPSHADE, "bench", scene, "--json", "--frames", "1", "--warmup", "0", "--loads", "5",
                       "--modes", "flat", "--threads", str(threads)]
            output = subprocess.run(command, check=True, capture_output=True, text=True, cwd=ROOT).stdout
            load = next(json.loads(line) for line in output.splitlines() if '"stage":"load"' in line)
            name = os.path.splitext(os.path.basename(scene))[0]
            print(f"| {name} | {load['bytes_read']:,} | {threads} | {load['median_ms']:.1f} | {load['mb_per_s']:.0f} |")


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
    parser.add_argument("--modes", default=",".join(MODES),
                        help="comma-separated shading modes of the anchor and real-mesh rows (the feature "
                        "scenes keep their own)")
    parser.add_argument("--scaling", action="store_true", help="also the triangle-count and resolution sweeps")
    parser.add_argument("--no-compare", action="store_true", help="skip the llvmpipe comparison")
    parser.add_argument("--scenes", help="comma-separated anchor names or shell patterns to compare "
                        "(`features`: every feature scene; `meshes`: every real-mesh scene); default: all")
    args = parser.parse_args()
    args.threads = [int(t) for t in args.threads.split(",")]
    args.modes = args.modes.split(",")
    args.scenes = args.scenes.split(",") if args.scenes else None
    args.anchors = os.path.abspath(args.anchors)
    if "LAMPSHADE" not in os.environ:
        # The checkout's own release build, brought up to date: a binary left from an earlier
        # commit would be measured silently otherwise.
        subprocess.run(["cargo", "build", "--release", "--quiet"], check=True, cwd=ROOT)
    if not os.path.exists(LAMPSHADE):
        sys.exit(f"no lampshade binary at {LAMPSHADE}")
    if not args.no_compare:
        work = build_glref(args.anchors)
        compare(args, work)
        compare_features(args, work)
        compare_meshes(args, work)
        shutil.rmtree(work, ignore_errors=True)
    if args.scaling:
        scaling(args)


if __name__ == "__main__":
    main()
