#!/usr/bin/python3
"""Writes an Inria cameras.json that circles a scene: `rings` of views looking at the median of
the Gaussians' centres, at 3 x the radius holding 90% of them, up = the given world axis.
The real trained scenes in tests/data come without cameras; the browser test uses this for the
cameras.json path (docs/web.md).

    make_orbit_cameras.py SCENE.ply OUT.json [--up 0,0,1] [--size 640x480] [--elev 45,15] [--per-ring 8]
Standard library only; binary little-endian PLY with x y z as the first three float properties.
"""
import argparse
import array
import json
import math


def read_xyz(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode("latin1").splitlines()
    n = next(int(l.split()[2]) for l in head if l.startswith("element vertex"))
    props = [l.split() for l in head if l.startswith("property")]
    if [p[2] for p in props[:3]] != ["x", "y", "z"] or any(p[1] != "float" for p in props):
        raise SystemExit(path + ": expected float properties starting with x y z")
    a = array.array("f")
    a.frombytes(data[end:end + n * len(props) * 4])
    k = len(props)
    return [(a[i * k], a[i * k + 1], a[i * k + 2]) for i in range(n)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--up", default="0,0,1")
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--elev", default="45,15")
    ap.add_argument("--per-ring", type=int, default=8)
    a = ap.parse_args()
    pts = read_xyz(a.scene)
    n = len(pts)
    c = [sorted(p[d] for p in pts)[n // 2] for d in range(3)]
    r90 = sorted(math.dist(c, p) for p in pts)[n * 9 // 10]
    up = [float(v) for v in a.up.split(",")]
    w, h = (int(v) for v in a.size.split("x"))
    f = 0.5 * w / math.tan(math.radians(25))  # 50 degrees across
    norm = lambda v: [x / math.sqrt(sum(y * y for y in v)) for x in v]
    cross = lambda u, v: [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    up = norm(up)
    e1 = norm(cross(up, [1, 0, 0] if abs(up[0]) < 0.9 else [0, 1, 0]))
    e2 = cross(up, e1)
    cams = []
    for ring, elev in enumerate(float(v) for v in a.elev.split(",")):
        for k in range(a.per_ring):
            az = 2 * math.pi * (k + 0.5 * ring) / a.per_ring
            d = [math.cos(math.radians(elev)) * (math.cos(az) * e1[i] + math.sin(az) * e2[i]) + math.sin(math.radians(elev)) * up[i] for i in range(3)]
            eye = [c[i] + 3 * r90 * d[i] for i in range(3)]
            z = norm([c[i] - eye[i] for i in range(3)])   # forward
            x = norm(cross(z, up))                         # right = forward x up (Camera::look_at)
            y = cross(z, x)                                # down
            rot = [[x[i], y[i], z[i]] for i in range(3)]  # camera-to-world, OpenCV axes as columns
            cams.append({"id": len(cams), "img_name": f"ring{ring}_{k}", "width": w, "height": h,
                         "position": eye, "rotation": rot, "fx": f, "fy": f})
    json.dump(cams, open(a.out, "w"), indent=1)


main()
