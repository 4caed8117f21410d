#!/usr/bin/env python3
"""Writes the two files the feature bench scenes need that lampshade cannot describe inline:

* scenes/bench/meshes/plane-64.obj: the llvmpipe anchor's `{"mesh": "plane", "n": 64}`
  (shared/anchors/llvmpipe README, "Plane mesh"): the square [-1,1]^2 at z = 0, normal +z, 64x64
  quads, vertex (i,j) = (-1 + 2j/N, -1 + 2i/N, 0) (normals computed by the loader). Each quad is written as the face
  v(i,j) v(i,j+1) v(i+1,j+1) v(i+1,j), which the OBJ loader fans from its first vertex into the
  anchor's two triangles in the anchor's order. lampshade's own `Plane` is two triangles in the XZ
  plane and has no subdivision, so the per-vertex modes (flat, gouraud) could not match.
* assets/textures/checker-noise-1024.png: the anchor's procedural texture
  (shared/anchors/llvmpipe/scenes/gen_texture.py, the same pattern, hash and noise, transcribed
  below), stored so that lampshade's decoding gives llvmpipe's texel values. glref uses the bytes
  linearly (byte/255); lampshade decodes every colour texture as sRGB and has no option to read one
  as linear. So each anchor byte g is stored as the 8-bit sRGB code whose decoded value is nearest
  to g/255 (within 1.1/255 for the brightest texels, closer below), as greyscale (R = G = B in the
  anchor's file).

Deterministic, standard library only: python3 scenes/bench/gen_feature_assets.py
"""
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PLANE = os.path.join(ROOT, "scenes", "bench", "meshes", "plane-64.obj")
TEXTURE = os.path.join(ROOT, "assets", "textures", "checker-noise-1024.png")

N = 64                   # plane quads per side
W = H = 1024             # texture size
CW, CH = 32, 64          # checker cell size in pixels
LAT = 16                 # noise lattice cells per side


def write_plane():
    lines = [f"# plane({N}) of the llvmpipe feature anchors; written by scenes/bench/gen_feature_assets.py",
             "# no normals: the loader computes them from the faces, exactly (0, 0, 1) on this plane"]
    for i in range(N + 1):
        for j in range(N + 1):
            # Multiples of 1/32: exact in decimal and in f32.
            lines.append(f"v {-1 + 2 * j / N:g} {-1 + 2 * i / N:g} 0")
    vertex = lambda i, j: i * (N + 1) + j + 1
    for i in range(N):
        for j in range(N):
            corners = (vertex(i, j), vertex(i, j + 1), vertex(i + 1, j + 1), vertex(i + 1, j))
            lines.append("f " + " ".join(str(c) for c in corners))
    os.makedirs(os.path.dirname(PLANE), exist_ok=True)
    with open(PLANE, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", PLANE)


def h(i, j):
    """deterministic hash -> [0,1) (gen_texture.py's)"""
    x = (i * 374761393 + j * 668265263) & 0xFFFFFFFF
    x = ((x ^ (x >> 13)) * 1274126177) & 0xFFFFFFFF
    return ((x ^ (x >> 16)) & 0xFFFF) / 65536.0


def srgb_to_linear(c):
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


# The sRGB code lampshade decodes to the value nearest each of glref's linear bytes.
DECODED = [srgb_to_linear(s / 255) for s in range(256)]
ENCODE = [min(range(256), key=lambda s: abs(DECODED[s] - g / 255)) for g in range(256)]


def anchor_byte(x, y, lat):
    """gen_texture.py's value of texel (x, y) as the byte it stores."""
    fy = y * LAT / H
    iy = int(fy); ty = fy - iy
    ty = ty * ty * (3 - 2 * ty)
    fx = x * LAT / W
    ix = int(fx); tx = fx - ix
    tx = tx * tx * (3 - 2 * tx)
    a = lat[iy][ix] + (lat[iy][ix + 1] - lat[iy][ix]) * tx
    b = lat[iy + 1][ix] + (lat[iy + 1][ix + 1] - lat[iy + 1][ix]) * tx
    n = 0.75 + 0.25 * (a + (b - a) * ty)
    base = 0.95 if ((x // CW) + (y // CH)) % 2 == 0 else 0.30
    v = base * n
    if x % (4 * CW) < 2 or y % (4 * CH) < 2:
        v = 0.05
    return int(round(v * 255))


def write_texture():
    lat = [[h(i % LAT, j % LAT) for j in range(LAT + 1)] for i in range(LAT + 1)]
    rows = []
    for y in range(H):
        row = bytearray([0])  # PNG filter type 0
        row += bytes(ENCODE[anchor_byte(x, y, lat)] for x in range(W))
        rows.append(bytes(row))

    def chunk(t, d):
        c = struct.pack(">I", len(d)) + t + d
        return c + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    # 8-bit greyscale (colour type 0).
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 0, 0, 0, 0)) \
        + chunk(b"IDAT", zlib.compress(b"".join(rows), 9)) + chunk(b"IEND", b"")
    os.makedirs(os.path.dirname(TEXTURE), exist_ok=True)
    with open(TEXTURE, "wb") as f:
        f.write(png)
    print("wrote", TEXTURE)


if __name__ == "__main__":
    write_plane()
    write_texture()
