#!/usr/bin/python3
"""Test helper: what an editor does to a scene on save. Writes a copy of a binary PLY whose
vertex rows are in reverse order (a re-sorted copy: same Gaussians, other indices); with
--edit, the first float of the (new) first row is also changed (an edited copy).
    reorder_ply.py IN.ply OUT.ply [--edit]
Only binary_little_endian files with a single fixed-size `vertex` element (vcar's writer)."""
import struct
import sys

SIZES = {"char": 1, "int8": 1, "uchar": 1, "uint8": 1, "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
         "int": 4, "int32": 4, "uint": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}


def main(argv):
    if len(argv) not in (3, 4) or (len(argv) == 4 and argv[3] != "--edit"):
        sys.exit(__doc__)
    data = open(argv[1], "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    if "format binary_little_endian 1.0" not in header:
        sys.exit("not a binary little-endian PLY")
    elements = [l for l in header if l.startswith("element ")]
    if len(elements) != 1 or not elements[0].startswith("element vertex "):
        sys.exit("expected a single vertex element")
    n = int(elements[0].split()[2])
    stride = sum(SIZES[l.split()[1]] for l in header if l.startswith("property "))
    rows = [data[end + i * stride:end + (i + 1) * stride] for i in range(n)]
    rows.reverse()
    if len(argv) == 4 and n > 0:
        (x,) = struct.unpack_from("<f", rows[0])
        rows[0] = struct.pack("<f", x + 0.125) + rows[0][4:]
    open(argv[2], "wb").write(data[:end] + b"".join(rows))


if __name__ == "__main__":
    main(sys.argv)
