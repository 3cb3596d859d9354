#!/usr/bin/env python3
"""Checks `vcar segment --prompts` against single runs (tests.cmake, cli/segment_objects_*).

usage: check_objects.py MULTI_DIR SINGLE_SELECTION OBJECT
  OBJECT's Gaussians in MULTI_DIR/selection.json are the single run's, less the ones another
  object took (each of those is in another object's selection, and counted in report.json);
  labels.ply names each object's Gaussians; objects/<OBJECT>.ply has as many rows.
"""
import json
import os
import struct
import sys


def ply_rows_and_labels(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    n = int([l for l in header if l.startswith("element vertex")][0].split()[2])
    props = [l.split() for l in header if l.startswith("property")]
    if props[-1] != ["property", "int", "label"]:
        return n, None
    row = 4 * (len(props) - 1) + 4
    labels = [struct.unpack_from("<i", data, end + r * row + row - 4)[0] for r in range(n)]
    return n, labels


def main(argv):
    multi_dir, single_path, name = argv[1], argv[2], argv[3]
    with open(os.path.join(multi_dir, "selection.json")) as f:
        multi = json.load(f)
    with open(single_path) as f:
        single = set(json.load(f)["indices"])
    with open(os.path.join(multi_dir, "report.json")) as f:
        report = json.load(f)
    objs = multi["objects"]
    k = [o["name"] for o in objs].index(name)
    mine = set(objs[k]["indices"])
    others = set().union(*[set(o["indices"]) for j, o in enumerate(objs) if j != k])
    errors = []
    if not mine <= single:
        errors.append("%d Gaussians not in the single run" % len(mine - single))
    if not (single - mine) <= others:
        errors.append("%d Gaussians of the single run are in no object" % len(single - mine - others))
    if report["objects"][k]["counts"]["lost_to_others"] != len(single - mine):
        errors.append("lost_to_others %d, expected %d" % (report["objects"][k]["counts"]["lost_to_others"], len(single - mine)))
    if mine & others:
        errors.append("objects overlap after conflicts were resolved")
    n, labels = ply_rows_and_labels(os.path.join(multi_dir, "labels.ply"))
    if labels is None or n != multi["scene_gaussians"]:
        errors.append("labels.ply: no int label or wrong size")
    else:
        if {i for i, l in enumerate(labels) if l == k} != mine:
            errors.append("labels.ply does not name object %d's Gaussians" % k)
    rows, _ = ply_rows_and_labels(os.path.join(multi_dir, "objects", name + ".ply"))
    if rows != len(mine):
        errors.append("objects/%s.ply has %d rows, the selection %d" % (name, rows, len(mine)))
    if errors:
        print("\n".join(errors))
        return 1
    print("%s: %d Gaussians, %d lost to other objects, single run %d" % (name, len(mine), len(single - mine), len(single)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
