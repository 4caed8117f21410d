#!/usr/bin/env python3
"""Writes the real-mesh bench scenes and their llvmpipe anchors from one table, so that the two
agree parameter for parameter:

* scenes/bench/{koala,koala-far,nefertiti,cow,cow-close,cow-textured,duck}.ron and
  benches/scenes/nefertiti-1m.ron (its mesh is generated: benches/gen_meshes.py), for lampshade;
* benches/anchors/s4_<scene with _ for ->.json, in the scene format of llvmpipe's harness
  (shared/anchors/llvmpipe/README.md, "Scene JSON"), for its `glref`.

    python3 benches/anchors/gen_real_mesh_scenes.py

The meshes: the koala scan (100k triangles, closed), the nefertiti scan (70k, open), Keenan
Crane's cow "Spot" (5,856 triangles with texture coordinates; named `cow` here because
scenes/bench/spot.ron is S1 with a spot light), the glTF Duck (4,212 triangles; the anchor reads
benches/meshes/duck.obj, an OBJ export with the same positions and normals), and nefertiti refined
to 1,120,000 triangles. All are y-up. Views: each model filling most of a 1920x1080 frame from the
front, right and above; `koala-far` the koala at about 120 pixels tall (its triangles smaller than
a pixel); `cow-close` the cow's head filling the frame (its triangles larger than a 64x64 tile).

Both renderers: a perspective camera with a vertical field of view of 30 degrees, global ambient
(1, 1, 1), two white directional lights and a dimmer point light (no attenuation, which is
glref's only kind) placed relative to each camera, one-sided lighting (`back_faces: Lit`), and one
material of final coefficients. Normals: glref computes the vertex normals of an OBJ without them
smooth over every face at a vertex (area weighted); lampshade's scenes ask for `crease_angle: 180`
(smooth everywhere, angle weighted): the images differ a little in shading, not in coverage.
`cow-textured` adds Spot's own texture; glref cannot texture an OBJ, so it has no anchor.
"""
import json
import math
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ANCHORS = os.path.join(ROOT, "benches", "anchors")
WIDTH, HEIGHT, FOV = 1920, 1080, 30

KOALA = "assets/obj/koala/koala.obj"
NEFERTITI = "assets/obj/nefertiti/nefertiti-lowres.obj"
COW = "assets/obj/spot/spot_triangulated.obj"
COW_TEXTURE = "assets/obj/spot/spot_texture.png"
DUCK_GLTF = "assets/gltf/Duck/glTF/Duck.gltf"
DUCK_OBJ = "benches/meshes/duck.obj"
NEFERTITI_1M = "benches/meshes/nefertiti-1m.obj"

# Final material coefficients (ambient = 0.1 of a clay colour, diffuse 0.6 of it, a white
# specular of 0.3) and shininess, as glref takes them.
CLAY = {"ambient": [0.08, 0.07, 0.06], "diffuse": [0.48, 0.42, 0.36], "specular": [0.3, 0.3, 0.3],
        "shininess": 20}
WHITE = {"ambient": [0.1, 0.1, 0.1], "diffuse": [0.6, 0.6, 0.6], "specular": [0.3, 0.3, 0.3],
         "shininess": 20}
YELLOW = {"ambient": [0.1, 0.08, 0.0], "diffuse": [0.6, 0.5, 0.05], "specular": [0.3, 0.3, 0.3],
          "shininess": 20}

# name, what, mesh for lampshade, mesh for glref (None: no anchor), material, texture,
# target, direction from target to eye, distance, where the scene file goes.
SCENES = [
    ("koala", "the koala scan (100k triangles, closed) filling most of the frame",
     KOALA, KOALA, CLAY, None, (0.0, 1.25, 0.4), (0.55, 0.3, 0.78), 14.0, "scenes/bench"),
    ("koala-far", "the koala scan far away, about 120 px tall: its triangles are smaller than a pixel",
     KOALA, KOALA, CLAY, None, (0.0, 1.25, 0.4), (0.55, 0.3, 0.78), 126.0, "scenes/bench"),
    ("nefertiti", "the nefertiti scan (70k triangles, open) filling most of the frame",
     NEFERTITI, NEFERTITI, CLAY, None, (0.0, 0.0, 0.0), (0.45, 0.1, 0.89), 1100.0, "scenes/bench"),
    ("cow", "Keenan Crane's cow Spot (5,856 triangles) filling most of the frame",
     COW, COW, WHITE, None, (0.0, 0.108, 0.19), (-0.5, 0.35, -0.8), 3.7, "scenes/bench"),
    ("cow-close", "the cow's head filling the frame: its triangles are larger than a 64x64 tile",
     COW, COW, WHITE, None, (0.0, 0.6, -0.5), (-0.5, 0.35, -0.8), 0.7, "scenes/bench"),
    ("cow-textured", "the cow of cow.ron with its own texture (spot_texture.png; no llvmpipe anchor: glref cannot texture an OBJ)",
     COW, None, WHITE, COW_TEXTURE, (0.0, 0.108, 0.19), (-0.5, 0.35, -0.8), 3.7, "scenes/bench"),
    ("duck", "the glTF Duck (4,212 triangles, its own normals) filling most of the frame",
     DUCK_GLTF, DUCK_OBJ, YELLOW, None, (0.135, 0.87, -0.035), (0.6, 0.45, -0.65), 3.7, "scenes/bench"),
    ("nefertiti-1m", "nefertiti refined to 1,120,000 triangles (benches/gen_meshes.py) filling most of the frame",
     NEFERTITI_1M, NEFERTITI_1M, CLAY, None, (0.0, 0.0, 0.0), (0.45, 0.1, 0.89), 1100.0, "benches/scenes"),
]


def normalized(v):
    length = math.sqrt(sum(c * c for c in v))
    return [c / length for c in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def rounded(v, digits=4):
    return [round(c, digits) + 0.0 for c in v]


def setup(target, direction, distance):
    """Camera and lights for a view along `direction` (towards the eye) at `distance`."""
    back = normalized(direction)
    eye = rounded([t + distance * b for t, b in zip(target, back)])
    right = normalized(cross([0.0, 1.0, 0.0], back))
    up = cross(back, right)
    # The key light from above and to the right of the eye, the fill from the left; the point
    # light above and to the left of the eye.
    key = rounded(normalized([b + 0.5 * r + 0.8 * u for b, r, u in zip(back, right, up)]))
    fill = rounded(normalized([0.6 * b - 0.9 * r + 0.2 * u for b, r, u in zip(back, right, up)]))
    point = rounded([e + 0.4 * distance * (u - r) for e, u, r in zip(eye, up, right)])
    camera = {"eye": eye, "target": list(target), "up": [0, 1, 0], "fovy_deg": FOV,
              "near": round(distance / 50, 4), "far": round(distance * 4, 4)}
    lights = [
        {"type": "directional", "direction_to_light": key, "color": [0.7, 0.7, 0.7]},
        {"type": "directional", "direction_to_light": fill, "color": [0.35, 0.35, 0.35]},
        {"type": "point", "position": point, "color": [0.25, 0.25, 0.25]},
    ]
    return camera, lights


def ron_vector(v):
    return "(" + ", ".join(f"{c:g}" for c in v) + ")"


def relative(path, folder):
    return os.path.relpath(os.path.join(ROOT, path), os.path.join(ROOT, folder))


def write_ron(name, what, mesh, anchor_mesh, material, texture, camera, lights, folder):
    stem = name.replace("-", "_")
    anchor = (f"llvmpipe anchor `s4_{stem}` (benches/anchors/s4_{stem}.json), parameter by parameter"
              if anchor_mesh else "no llvmpipe anchor")
    key, fill, point = lights
    mesh_kind = "Gltf" if mesh.endswith(".gltf") else "Obj"
    texture_field = f", texture: \"{relative(texture, folder)}\"" if texture else ""
    text = f"""// Real-mesh bench scene `{name}`: {anchor}. Written by
// benches/anchors/gen_real_mesh_scenes.py: {what}.
// GL conventions as in two-spheres.ron: global ambient, lights with no ambient part and no
// attenuation, one-sided lighting (`back_faces: Lit`). Normals smooth across every edge
// (`crease_angle: 180`), as llvmpipe's harness computes them for an OBJ without normals.
// The shading mode is chosen with `--shading`/`--model` (or per mode by `lampshade bench`).
Scene(
    image: (width: {WIDTH}, height: {HEIGHT}, background: (0, 0, 0)),
    camera: Perspective(eye: {ron_vector(camera["eye"])}, target: {ron_vector(camera["target"])}, up: (0, 1, 0), fov: {FOV}, near: {camera["near"]:g}, far: {camera["far"]:g}),
    ambient: (1, 1, 1),
    lights: [
        Directional(direction: {ron_vector([-c for c in key["direction_to_light"]])}, color: {ron_vector(key["color"])}),
        Directional(direction: {ron_vector([-c for c in fill["direction_to_light"]])}, color: {ron_vector(fill["color"])}),
        Point(position: {ron_vector(point["position"])}, color: {ron_vector(point["color"])}, attenuation: (constant: 1, linear: 0, quadratic: 0)),
    ],
    objects: [
        (mesh: {mesh_kind}("{relative(mesh, folder)}"), back_faces: Lit, crease_angle: 180, material: (ambient: {ron_vector(material["ambient"])}, diffuse: {ron_vector(material["diffuse"])}, specular: {ron_vector(material["specular"])}, shininess: {material["shininess"]}{texture_field})),
    ],
)
"""
    path = os.path.join(ROOT, folder, name + ".ron")
    with open(path, "w") as out:
        out.write(text)
    print("wrote", os.path.relpath(path, ROOT))


def write_anchor(name, what, anchor_mesh, material, camera, lights):
    stem = "s4_" + name.replace("-", "_")
    scene = {
        "name": stem,
        "description": what + "; written by benches/anchors/gen_real_mesh_scenes.py",
        "width": WIDTH, "height": HEIGHT, "background": [0, 0, 0],
        "camera": camera,
        "ambient_light": [1, 1, 1],
        "lights": lights,
        "objects": [{"mesh": "obj", "path": relative(anchor_mesh, "benches/anchors"),
                     "translate": [0, 0, 0], "scale": 1, "material": material}],
    }
    path = os.path.join(ANCHORS, stem + ".json")
    with open(path, "w") as out:
        json.dump(scene, out, indent=1)
        out.write("\n")
    print("wrote", os.path.relpath(path, ROOT))


def main():
    for name, what, mesh, anchor_mesh, material, texture, target, direction, distance, folder in SCENES:
        camera, lights = setup(target, direction, distance)
        write_ron(name, what, mesh, anchor_mesh, material, texture, camera, lights, folder)
        if anchor_mesh:
            write_anchor(name, what, anchor_mesh, material, camera, lights)


if __name__ == "__main__":
    main()
