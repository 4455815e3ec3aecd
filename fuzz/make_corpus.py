#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes the seed corpora of the fuzz targets: fuzz/corpus/<target>/<name>.

Small valid and invalid files: ASCII and binary (both endiannesses) PLY with and
without normals, with extra properties, lists (faces) before and after the vertices,
comments, every scalar type; .xyz with 3 and 6 columns, comments, blank lines, CRLF
line endings, exponents and many digits. Run from anywhere: python3 fuzz/make_corpus.py
(it replaces the seed files it writes and leaves other files alone)."""

import math
import os
import struct

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")

TYPES = {  # PLY name -> struct code
    "char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
    "float": "f", "double": "d",
    "int8": "b", "uint8": "B", "int16": "h", "uint16": "H", "int32": "i", "uint32": "I",
    "float32": "f", "float64": "d",
}


def point(i):
    t = 0.7 * i
    return (math.cos(t) * 1.5, math.sin(t) * 0.5, 0.1 * i - 0.3)


def normal(i):
    t = 0.7 * i
    return (math.cos(t), math.sin(t), 0.0 if i % 3 else -0.5)


def header(fmt, elements, comments=("comment seed",)):
    """elements: list of (name, count, [(type, name) or ('list', count_type, item_type, name)])"""
    text = "ply\nformat %s 1.0\n" % fmt
    for c in comments:
        text += c + "\n"
    for name, count, properties in elements:
        text += "element %s %d\n" % (name, count)
        for p in properties:
            if p[0] == "list":
                text += "property list %s %s %s\n" % (p[1], p[2], p[3])
            else:
                text += "property %s %s\n" % p
    return (text + "end_header\n").encode()


def value_of(type_name, v):
    code = TYPES[type_name]
    if code in "fd":
        return v
    return int(v)


def encode_row(fmt, properties, values):
    """values: one per property; a list value for a list property."""
    if fmt == "ascii":
        out = []
        for p, v in zip(properties, values):
            if p[0] == "list":
                out.append(str(len(v)))
                out.extend(str(x) for x in v)
            else:
                out.append(repr(value_of(p[0], v)) if TYPES[p[0]] in "fd" else str(int(v)))
        return (" ".join(out) + "\n").encode()
    endian = "<" if fmt == "binary_little_endian" else ">"
    data = b""
    for p, v in zip(properties, values):
        if p[0] == "list":
            data += struct.pack(endian + TYPES[p[1]], len(v))
            data += b"".join(struct.pack(endian + TYPES[p[2]], value_of(p[2], x)) for x in v)
        else:
            data += struct.pack(endian + TYPES[p[0]], value_of(p[0], v))
    return data


def ply(fmt, n, point_type="float", normals=None, extras=(), faces_before=0, faces_after=0,
        comments=("comment seed",)):
    vertex = [(point_type, "x"), (point_type, "y"), (point_type, "z")]
    if normals:
        vertex += [(normals, "nx"), (normals, "ny"), (normals, "nz")]
    vertex += list(extras)
    face = [("list", "uchar", "int", "vertex_indices")]
    elements = []
    if faces_before:
        elements.append(("edge", faces_before, face))
    elements.append(("vertex", n, vertex))
    if faces_after:
        elements.append(("face", faces_after, face))
    data = header(fmt, elements, comments)

    def faces(count):
        return b"".join(encode_row(fmt, face, [[(f + k) % max(n, 1) for k in range(3 + f % 2)]])
                        for f in range(count))

    data += faces(faces_before)
    for i in range(n):
        values = list(point(i))
        if normals:
            values += list(normal(i))
        values += [(7 * i + k) % 100 for k in range(len(extras))]
        data += encode_row(fmt, vertex, values)
    return data + faces(faces_after)


def xyz(n, normals, newline="\n", fmt="%.6f"):
    lines = []
    for i in range(n):
        values = list(point(i)) + (list(normal(i)) if normals else [])
        lines.append(" ".join(fmt % v for v in values))
    return (newline.join(lines) + newline).encode()


def write(target, name, data):
    directory = os.path.join(ROOT, target)
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, name), "wb") as f:
        f.write(data)


def main():
    colours = [("uchar", "red"), ("uchar", "green"), ("uchar", "blue")]
    every_type = [(t, "p_" + t) for t in ("char", "uchar", "short", "ushort", "int", "uint", "float", "double")]
    ascii_header = header("ascii", [("vertex", 3, [("float", "x"), ("float", "y"), ("float", "z")])])
    binary_header = header("binary_little_endian", [("vertex", 3, [("float", "x"), ("float", "y"), ("float", "z")])])
    plys = {
        # valid
        "ascii_points.ply": ply("ascii", 5),
        "ascii_normals_comments.ply": ply("ascii", 4, normals="float",
                                          comments=("comment made by hand", "obj_info scanner 1")),
        "ascii_colours_faces.ply": ply("ascii", 6, normals="float", extras=colours, faces_after=2),
        "ascii_face_before.ply": ply("ascii", 4, point_type="double", faces_before=2),
        "ascii_crlf.ply": ply("ascii", 3, normals="double").replace(b"\n", b"\r\n"),
        "ascii_empty.ply": ply("ascii", 0),
        "binary_le_points.ply": ply("binary_little_endian", 4),
        "binary_le_normals.ply": ply("binary_little_endian", 5, normals="float"),
        "binary_le_double_extras.ply": ply("binary_little_endian", 4, point_type="double", normals="float",
                                           extras=colours + [("int", "label")], faces_after=3),
        "binary_be_every_type.ply": ply("binary_big_endian", 3, point_type="double", normals="double",
                                        extras=every_type),
        "binary_be_face_before.ply": ply("binary_big_endian", 3, normals="float", faces_before=2, faces_after=1),
        "binary_sized_types.ply": ply("binary_little_endian", 3, point_type="float32", normals="float64",
                                      extras=[("uint8", "alpha"), ("int16", "id")]),
        "binary_integer_points.ply": ply("binary_little_endian", 3, point_type="short", extras=[("uchar", "red")]),
        "binary_empty.ply": ply("binary_little_endian", 0, normals="float", faces_after=0),
        "binary_float_extremes.ply": header("binary_little_endian", [("vertex", 3, [
            ("float", "x"), ("float", "y"), ("float", "z"), ("float", "nx"), ("float", "ny"), ("float", "nz"),
            ("double", "quality"), ("float", "intensity")])])
        + struct.pack("<6fdf", 3.4028234663852886e38, -3.4028234663852886e38, 1.401298464324817e-45,
                      -0.0, 1.1754943508222875e-38, 0.1, 5e-324, float("nan"))
        + struct.pack("<6fdf", 1, 2, 3, 0, 0, 0, float("inf"), float("-inf"))
        + struct.pack("<6fdf", -1e-30, 1e30, 16777217.0, 1, 0, 0, 1.7976931348623157e308, -0.0),
        "ascii_number_forms.ply": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty double y\n"
                                  b"property short z\nproperty uchar red\nproperty float s\nend_header\n"
                                  b"3.4028235e+38 -0 -0.0 255.0 1e-50\n"
                                  b"+1.5 1e-310 +12 -0 nan\n"
                                  b"-3.4028235e38 .5 1e2 +7 -inf\n",
        # invalid
        "bad_keyword.ply": b"ply\nformat ascii 1.0\nelemnt vertex 1\nend_header\n1 2 3\n",
        "bad_type.ply": b"ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n1\n",
        "bad_list_in_vertex.ply": b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                  b"property float z\nproperty list uchar int n\nend_header\n1 2 3 0\n",
        "bad_no_end_header.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n",
        "bad_ascii_nan.ply": ascii_header + b"1 2 3\nnan 0 0\n4 5 6\n",
        "bad_ascii_short_line.ply": ascii_header + b"1 2 3\n4 5\n6 7 8\n",
        "bad_ascii_truncated.ply": ascii_header + b"1 2 3\n",
        "bad_ascii_token.ply": ascii_header + b"1 2 3\n4 five 6\n7 8 9\n",
        "bad_binary_truncated.ply": binary_header + struct.pack("<7f", 1, 2, 3, 4, 5, 6, 7),
        "bad_binary_inf.ply": binary_header + struct.pack("<9f", 1, 2, 3, float("inf"), 5, 6, 7, 8, 9),
        "bad_binary_trailing.ply": binary_header + struct.pack("<9f", 1, 2, 3, 4, 5, 6, 7, 8, 9) + b"junk",
        "bad_count_too_large.ply": header("binary_little_endian",
                                          [("vertex", 10 ** 12, [("float", "x"), ("float", "y"), ("float", "z")])])
                                   + struct.pack("<3f", 1, 2, 3),
    }
    xyzs = {
        # valid
        "points.xyz": xyz(8, False),
        "normals.xyz": xyz(8, True),
        "comments_blank_lines.xyz": b"# x y z nx ny nz\n\n" + xyz(3, True) + b"\n   \n# end\n",
        "crlf_tabs.xyz": xyz(4, False, newline="\r\n").replace(b" ", b"\t"),
        "exponents.xyz": b"1e-5 -0 +1.5\n.5 5. -2.5E+3\n1.0000000000000002 0.1 123456789012345678\n"
                         b"4.9e-324 -1.7976931348623157e308 0.000\n",
        "digits.xyz": xyz(5, True, fmt="%.17g"),
        "many_lines.xyz": xyz(120, True, fmt="%.3f"),
        "no_final_newline.xyz": b"1 2 3\n4 5 6",
        "empty.xyz": b"",
        # invalid
        "bad_mixed_columns.xyz": b"1 2 3\n1 2 3 0 0 1\n",
        "bad_four_columns.xyz": b"1 2 3 4\n",
        "bad_two_columns.xyz": b"# two\n1 2\n",
        "bad_text.xyz": b"1 2 3\nx y z\n",
        "bad_nan.xyz": b"1 2 3\nnan 2 3\n",
        "bad_inf_normal.xyz": b"1 2 3 0 0 1\n1 2 3 0 inf 1\n",
        "bad_out_of_range.xyz": b"1 2 1e999\n",
        "bad_trailing_comment.xyz": b"1 2 3 # a point\n",
    }
    for name, data in plys.items():
        write("fuzz_read_ply", name, data)
        write("fuzz_stream_reader", name, data)
    for name, data in xyzs.items():
        write("fuzz_read_xyz", name, data)
        write("fuzz_stream_reader", name, data)


if __name__ == "__main__":
    main()
