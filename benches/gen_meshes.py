#!/usr/bin/env python3
"""Writes the two meshes of the real-mesh benchmarks that are generated rather than committed, into
benches/meshes/ (ignored by git; benches/llvmpipe.py runs this script when one is missing).
Deterministic, standard library only, a few seconds (name meshes to write only those, e.g.
`python3 benches/gen_meshes.py sphere-gltf`):

    python3 benches/gen_meshes.py

* nefertiti-1m.obj (about 40 MB): the nefertiti scan (assets/obj/nefertiti, 70,000 triangles)
  refined by two levels of Loop subdivision into 1,120,000 triangles: the bench scene of about a
  million triangles (benches/scenes/nefertiti-1m.ron; its llvmpipe anchor
  benches/anchors/s4_nefertiti_1m.json).
* duck.obj: the glTF Duck (assets/gltf/Duck/glTF) as llvmpipe's harness can read it (it reads OBJ
  only): its one primitive with the scene's transform (the root node's scale of 0.01) applied to
  the positions, and its normals, so that both renderers light the same normals
  (benches/anchors/s4_duck.json; lampshade's scenes/bench/duck.ron reads the glTF itself).
* sphere-gltf/sphere.gltf with sphere.bin (about 29 MB): a latitude-longitude unit sphere of
  512 rings by 1,024 segments (525,825 vertices, 1,048,576 triangles, the poles' degenerate
  ones included) with its exact normals and texture coordinates, as tightly packed float
  accessors and 32-bit indices: the glTF loading benchmark (benches/scenes/sphere-gltf.ron),
  where reading accessors is most of the load.

Loop subdivision (Loop 1987, with Warren's weights): every triangle becomes four, its corners
moved to (1 - n*b) v + b * (sum of the n neighbours), b = 3/(8n) (3/16 when n = 3), and a new
vertex on each edge at 3/8 (a + b) + 1/8 (c + d) for the edge (a, b) between the triangles with
third corners c and d. The scan is open: an edge with one triangle is a boundary, its new vertex
at its midpoint, and a corner on exactly two boundary edges moves to 3/4 v + 1/8 (b1 + b2); an
edge with more than two triangles (none in this scan) would count as a boundary, and a corner on
it stays put. Each triangle's four children follow each other in the parent's place, so the file
keeps the scan's order of triangles; the corners keep their numbers and the edge vertices follow
in the order their first triangle meets them.
"""
import json
import os
import struct
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCE = os.path.join(ROOT, "assets", "obj", "nefertiti", "nefertiti-lowres.obj")
TARGET = os.path.join(ROOT, "benches", "meshes", "nefertiti-1m.obj")
LEVELS = 2
DUCK = os.path.join(ROOT, "assets", "gltf", "Duck", "glTF", "Duck.gltf")
DUCK_TARGET = os.path.join(ROOT, "benches", "meshes", "duck.obj")
SPHERE_TARGET = os.path.join(ROOT, "benches", "meshes", "sphere-gltf", "sphere.gltf")
SPHERE_RINGS, SPHERE_SEGMENTS = 512, 1024


def read_obj(path):
    xs, ys, zs, faces = [], [], [], []
    with open(path) as lines:
        for line in lines:
            words = line.split()
            if not words:
                continue
            if words[0] == "v":
                xs.append(float(words[1]))
                ys.append(float(words[2]))
                zs.append(float(words[3]))
            elif words[0] == "f":
                corners = [int(word.split("/")[0]) - 1 for word in words[1:]]
                for k in range(1, len(corners) - 1):
                    faces.append((corners[0], corners[k], corners[k + 1]))
    return xs, ys, zs, faces


def subdivide(xs, ys, zs, faces):
    n = len(xs)
    # Each edge (by its smaller and larger corner) with the third corners of its triangles.
    opposite = {}
    for a, b, c in faces:
        for u, v, w in ((a, b, c), (b, c, a), (c, a, b)):
            key = u * n + v if u < v else v * n + u
            opposite.setdefault(key, []).append(w)

    # Corners: neighbour sums over interior edges, boundary neighbours.
    sx, sy, sz = [0.0] * n, [0.0] * n, [0.0] * n
    neighbours = [0] * n
    boundary = [[] for _ in range(n)]
    pinned = [False] * n
    for key, thirds in opposite.items():
        u, v = divmod(key, n)
        sx[u] += xs[v]; sy[u] += ys[v]; sz[u] += zs[v]
        sx[v] += xs[u]; sy[v] += ys[u]; sz[v] += zs[u]
        neighbours[u] += 1
        neighbours[v] += 1
        if len(thirds) == 1:
            boundary[u].append(v)
            boundary[v].append(u)
        elif len(thirds) > 2:
            pinned[u] = pinned[v] = True
    nx, ny, nz = [], [], []
    for i in range(n):
        if pinned[i] or (boundary[i] and len(boundary[i]) != 2):
            nx.append(xs[i]); ny.append(ys[i]); nz.append(zs[i])
        elif boundary[i]:
            p, q = boundary[i]
            nx.append(0.75 * xs[i] + 0.125 * (xs[p] + xs[q]))
            ny.append(0.75 * ys[i] + 0.125 * (ys[p] + ys[q]))
            nz.append(0.75 * zs[i] + 0.125 * (zs[p] + zs[q]))
        elif neighbours[i] == 0:
            nx.append(xs[i]); ny.append(ys[i]); nz.append(zs[i])
        else:
            k = neighbours[i]
            beta = 3.0 / 16.0 if k == 3 else 3.0 / (8.0 * k)
            keep = 1.0 - k * beta
            nx.append(keep * xs[i] + beta * sx[i])
            ny.append(keep * ys[i] + beta * sy[i])
            nz.append(keep * zs[i] + beta * sz[i])

    # Edge vertices, numbered as the triangles meet them; then the children.
    edge_vertex = {}
    children = []
    for a, b, c in faces:
        mids = []
        for u, v in ((a, b), (b, c), (c, a)):
            key = u * n + v if u < v else v * n + u
            vertex = edge_vertex.get(key)
            if vertex is None:
                vertex = len(nx)
                edge_vertex[key] = vertex
                thirds = opposite[key]
                if len(thirds) == 2:
                    p, q = thirds
                    nx.append(0.375 * (xs[u] + xs[v]) + 0.125 * (xs[p] + xs[q]))
                    ny.append(0.375 * (ys[u] + ys[v]) + 0.125 * (ys[p] + ys[q]))
                    nz.append(0.375 * (zs[u] + zs[v]) + 0.125 * (zs[p] + zs[q]))
                else:
                    nx.append(0.5 * (xs[u] + xs[v]))
                    ny.append(0.5 * (ys[u] + ys[v]))
                    nz.append(0.5 * (zs[u] + zs[v]))
            mids.append(vertex)
        ab, bc, ca = mids
        children += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    return nx, ny, nz, children


def write_atomically(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    temporary = path + ".partial"
    with open(temporary, "w") as out:
        out.write(text)
    os.replace(temporary, path)


def write_dense_scan():
    xs, ys, zs, faces = read_obj(SOURCE)
    for _ in range(LEVELS):
        xs, ys, zs, faces = subdivide(xs, ys, zs, faces)
    write_atomically(TARGET, "".join([
        f"# nefertiti-lowres.obj (assets/obj/nefertiti) after {LEVELS} levels of Loop subdivision;\n",
        "# written by benches/gen_meshes.py\n",
        "".join(f"v {x:.5f} {y:.5f} {z:.5f}\n" for x, y, z in zip(xs, ys, zs)),
        "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces),
    ]))
    print(f"wrote {TARGET}: {len(xs):,} vertices, {len(faces):,} triangles", file=sys.stderr)


def accessor(document, buffer, index):
    """The elements of a float or unsigned-short accessor, as tuples (scalars as 1-tuples)."""
    description = document["accessors"][index]
    view = document["bufferViews"][description["bufferView"]]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[description["type"]]
    code, size = {5126: ("f", 4), 5123: ("H", 2), 5125: ("I", 4)}[description["componentType"]]
    stride = view.get("byteStride", width * size)
    start = view.get("byteOffset", 0) + description.get("byteOffset", 0)
    return [struct.unpack_from(f"<{width}{code}", buffer, start + i * stride) for i in range(description["count"])]


def write_duck():
    with open(DUCK) as file:
        document = json.load(file)
    with open(os.path.join(os.path.dirname(DUCK), document["buffers"][0]["uri"]), "rb") as file:
        buffer = file.read()
    # The default scene: node 0 (a uniform scale, column-major) holds node 2, which has the mesh.
    scale = document["nodes"][0]["matrix"][0]
    assert document["nodes"][0]["matrix"] == [scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, 1]
    primitive, = document["meshes"][0]["primitives"]
    positions = accessor(document, buffer, primitive["attributes"]["POSITION"])
    normals = accessor(document, buffer, primitive["attributes"]["NORMAL"])
    indices = [i for i, in accessor(document, buffer, primitive["indices"])]
    lines = ["# assets/gltf/Duck/glTF/Duck.gltf (© 2006 Sony Computer Entertainment Inc., SCEA Shared Source",
             "# License 1.0, assets/licenses/SCEA.txt) scaled by its root node; written by benches/gen_meshes.py"]
    lines += [f"v {x * scale:.7g} {y * scale:.7g} {z * scale:.7g}" for x, y, z in positions]
    lines += [f"vn {x:.7g} {y:.7g} {z:.7g}" for x, y, z in normals]
    lines += [f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}"
              for a, b, c in zip(indices[0::3], indices[1::3], indices[2::3])]
    write_atomically(DUCK_TARGET, "\n".join(lines) + "\n")
    print(f"wrote {DUCK_TARGET}: {len(positions):,} vertices, {len(indices) // 3:,} triangles", file=sys.stderr)


def write_sphere_gltf():
    import math
    from array import array
    positions, normals, uvs, indices = array("f"), array("f"), array("f"), array("I")
    for ring in range(SPHERE_RINGS + 1):
        theta = math.pi * ring / SPHERE_RINGS
        for segment in range(SPHERE_SEGMENTS + 1):
            phi = 2.0 * math.pi * segment / SPHERE_SEGMENTS
            point = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            positions.extend(point)
            normals.extend(point)
            uvs.extend((segment / SPHERE_SEGMENTS, ring / SPHERE_RINGS))
    row = SPHERE_SEGMENTS + 1
    for ring in range(SPHERE_RINGS):
        for segment in range(SPHERE_SEGMENTS):
            a = ring * row + segment
            b, c, d = a + row, a + 1, a + row + 1
            indices.extend((a, b, c, c, b, d))
    if sys.byteorder != "little":
        for values in (positions, normals, uvs, indices):
            values.byteswap()
    parts = [positions.tobytes(), normals.tobytes(), uvs.tobytes(), indices.tobytes()]
    views, offset = [], 0
    for part in parts:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(part)})
        offset += len(part)
    vertices = len(positions) // 3
    document = {
        "asset": {"version": "2.0", "generator": "benches/gen_meshes.py"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
        "buffers": [{"uri": "sphere.bin", "byteLength": offset}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": vertices, "type": "VEC3", "min": [-1, -1, -1], "max": [1, 1, 1]},
            {"bufferView": 1, "componentType": 5126, "count": vertices, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": vertices, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        ],
    }
    binary = os.path.join(os.path.dirname(SPHERE_TARGET), "sphere.bin")
    os.makedirs(os.path.dirname(binary), exist_ok=True)
    with open(binary + ".partial", "wb") as out:
        out.write(b"".join(parts))
    os.replace(binary + ".partial", binary)
    write_atomically(SPHERE_TARGET, json.dumps(document, indent=1) + "\n")
    print(f"wrote {SPHERE_TARGET}: {vertices:,} vertices, {len(indices) // 3:,} triangles", file=sys.stderr)


MESHES = {"nefertiti-1m": write_dense_scan, "duck": write_duck, "sphere-gltf": write_sphere_gltf}


def main():
    for name in sys.argv[1:] or MESHES:
        MESHES[name]()


if __name__ == "__main__":
    main()
