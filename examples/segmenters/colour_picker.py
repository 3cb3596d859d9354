#!/usr/bin/python3
"""A tiny segmenter for the vcar external-segmenter protocol (docs/cli.md), standard library only.

It picks the colour of frame 0 at the first positive prompt point and marks, in every frame,
the pixels whose colour is within --tol of it (max channel difference). Good enough for the
synthetic scenes, whose target has its own colour; used by the protocol tests.

    colour_picker.py [--tol T] [--fail STATUS] [--sleep S] [--bad-size] [--garbage]
                     [--skip K] [--require-boxes] REQUEST_DIR

Several objects (prompt.json "objects", `vcar segment --prompts`): each object's colour is
picked on its own frame ("frame") at its first positive point, and its masks go to
masks/<name>/NNNNN.png for the frames of its range ("frames": [first, count]; a batched round
gives each object its own frames).

Misbehaviours for tests: --fail exits with STATUS before writing anything, --sleep waits S
seconds first, --bad-size writes frame 0's mask one pixel too wide, --garbage writes a mask file
that is not a PNG, --skip K writes no mask for frame K. --require-boxes checks prompt.json's
"boxes" (one per frame, [x0, y0, x1, y1] inside the frame or null; frame 0's holds the first
positive point) and exits with status 65 when they are missing or wrong.
"""
import json
import os
import struct
import sys
import time
import zlib


def read_png(path):
    """Decodes an 8-bit, non-interlaced PNG (grey, grey+alpha, RGB, RGBA) -> (w, h, c, rows)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(path + ": not a PNG")
    pos, idat, w = 8, b"", None
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or interlace != 0 or ctype not in (0, 2, 4, 6):
                raise ValueError(path + ": unsupported PNG layout")
            c = {0: 1, 2: 3, 4: 2, 6: 4}[ctype]
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    raw = zlib.decompress(idat)
    stride = w * c
    rows, prev = [], bytearray(stride)
    for y in range(h):
        ftype = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - c] if x >= c else 0
            b = prev[x]
            cc = prev[x - c] if x >= c else 0
            if ftype == 1:
                line[x] = (line[x] + a) & 255
            elif ftype == 2:
                line[x] = (line[x] + b) & 255
            elif ftype == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - cc
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - cc)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else cc)
                line[x] = (line[x] + pred) & 255
        rows.append(line)
        prev = line
    return w, h, c, rows


def write_png_grey(path, w, h, rows):
    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
    tmp = path + ".part"
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


def check_boxes(prompt, cams):
    """What is wrong with prompt.json's "boxes" (None when nothing)."""
    boxes = prompt.get("boxes")
    if not isinstance(boxes, list) or len(boxes) != len(cams):
        return "expected a list of %d boxes, got %r" % (len(cams), boxes)
    for k, (b, cam) in enumerate(zip(boxes, cams)):
        if b is None:
            continue
        if len(b) != 4 or not (0 <= b[0] < b[2] <= cam["width"] and 0 <= b[1] < b[3] <= cam["height"]):
            return "frame %d: %r is not a box inside %dx%d" % (k, b, cam["width"], cam["height"])
    pts = [p for p, l in zip(prompt["points"], prompt["point_labels"]) if l == 1]
    b = boxes[0]
    if pts and (b is None or not (b[0] <= pts[0][0] <= b[2] and b[1] <= pts[0][1] <= b[3])):
        return "frame 0's box %r does not hold the first positive point %r" % (b, pts[0])
    return None


def main(argv):
    tol, fail, sleep, bad_size, garbage, skip, require_boxes = 40, None, 0.0, False, False, -1, False
    args = argv[1:]
    while len(args) > 1:
        a = args.pop(0)
        if a == "--tol":
            tol = int(args.pop(0))
        elif a == "--fail":
            fail = int(args.pop(0))
        elif a == "--sleep":
            sleep = float(args.pop(0))
        elif a == "--bad-size":
            bad_size = True
        elif a == "--garbage":
            garbage = True
        elif a == "--skip":
            skip = int(args.pop(0))
        elif a == "--require-boxes":
            require_boxes = True
        else:
            print("colour_picker: unknown option " + a, file=sys.stderr)
            return 64
    if len(args) != 1:
        print("usage: colour_picker.py [options] REQUEST_DIR", file=sys.stderr)
        return 64
    req = args[0]
    if sleep > 0:
        time.sleep(sleep)
    if fail is not None:
        print("colour_picker: failing on purpose with status %d" % fail, file=sys.stderr)
        return fail
    with open(os.path.join(req, "prompt.json")) as f:
        prompt = json.load(f)
    with open(os.path.join(req, "cameras.json")) as f:
        cams = json.load(f)
    if require_boxes:
        problem = check_boxes(prompt, cams)
        if problem:
            print("colour_picker: prompt.json \"boxes\": " + problem, file=sys.stderr)
            return 65
    objects = prompt.get("objects")
    if objects is None:  # one object: its prompt is on frame 0, masks in masks/
        objects = [dict(prompt, name="", frame=0, frames=[0, len(cams)])]
    frames = [read_png(os.path.join(req, "frames", cam["img_name"] + ".png")) for cam in cams]
    for obj in objects:
        pts = [p for p, l in zip(obj["points"], obj["point_labels"]) if l == 1]
        if not pts:
            print("colour_picker: needs a positive point (object %r)" % obj["name"], file=sys.stderr)
            return 2
        w, h, c, rows = frames[obj["frame"]]
        u, v = int(pts[0][0]), int(pts[0][1])
        target = rows[v][u * c:u * c + 3]
        out_dir = os.path.join(req, "masks", obj["name"]) if obj["name"] else os.path.join(req, "masks")
        os.makedirs(out_dir, exist_ok=True)
        first, count = obj.get("frames", [0, len(cams)])  # the frames this object is asked about
        for k in range(first, first + count):
            cam = cams[k]
            stem = cam["img_name"]
            w, h, c, rows = frames[k]
            out = os.path.join(out_dir, stem + ".png")
            if k == skip:
                continue
            if garbage and k == 0:
                with open(out, "wb") as f:
                    f.write(b"this is not a png")
                continue
            mask = []
            for r in rows:
                mask.append(bytearray(
                    255 if max(abs(r[x * c + i] - target[i]) for i in range(3)) <= tol else 0
                    for x in range(w)))
            if bad_size and k == 0:
                mask = [m + b"\x00" for m in mask]
                w += 1
            write_png_grey(out, w, h, mask)
    print("colour_picker: %d frames, %d objects, last colour %s" % (len(cams), len(objects), list(target)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
