#!/usr/bin/env python3
"""Regenerates tests/fuzz/seeds/ (committed; run only to change them): small VALID inputs that exercise every
feature of the readers, so the fuzzers start from deep paths. tools/fuzz.sh adds tests/data/bad,
tests/data/events and tests/data/sequences, and the corpus the fuzzers grew in earlier runs.
seeds/events/ is not generated here: it holds event files written by the tracker (`topotrack improve --events`,
`topotrack track`), kept as they were.
"""
import math
import os
import shutil
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = os.path.join(HERE, "seeds")


def put(kind, name, data):
    os.makedirs(os.path.join(SEEDS, kind), exist_ok=True)
    with open(os.path.join(SEEDS, kind, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def uv_sphere(rings=4, sectors=6):
    """A closed triangulated sphere: poles plus rings x sectors."""
    v = [(0.0, 0.0, 1.0)]
    for r in range(1, rings):
        th = math.pi * r / rings
        for s in range(sectors):
            ph = 2 * math.pi * s / sectors
            v.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
    v.append((0.0, 0.0, -1.0))
    f, south = [], len(v) - 1
    ring = lambda r, s: 1 + (r - 1) * sectors + s % sectors
    for s in range(sectors):
        f.append((0, ring(1, s), ring(1, s + 1)))
        f.append((south, ring(rings - 1, s + 1), ring(rings - 1, s)))
    for r in range(1, rings - 1):
        for s in range(sectors):
            a, b, c, d = ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1)
            f += [(a, c, b), (b, c, d)]
    return v, f


CUBE_V = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
CUBE_Q = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def ply(fmt, v, f, ids=False, color=False, normal=False, vel=False, extra=False, idx="int", cnt="uchar", pos="float"):
    props = [(pos, "x"), (pos, "y"), (pos, "z")]
    if normal: props += [("float", "nx"), ("float", "ny"), ("float", "nz")]
    if color: props += [("uchar", "red"), ("uchar", "green"), ("uchar", "blue"), ("uchar", "alpha")]
    if vel: props += [("double", "vx"), ("double", "vy"), ("double", "vz")]
    if ids: props += [("int", "id")]
    h = f"ply\nformat {fmt} 1.0\ncomment fuzz seed\nobj_info seed\nelement vertex {len(v)}\n"
    h += "".join(f"property {t} {n}\n" for t, n in props)
    if extra: h += "element material 2\nproperty list uchar float coeffs\nproperty short tag\n"
    h += f"element face {len(f)}\nproperty list {cnt} {idx} vertex_indices\nend_header\n"

    def values(i, p):
        out = list(p)
        if normal: out += list(p)
        if color: out += [(40 * i) % 256, 128, 255, 255]
        if vel: out += [0.5, -0.25, 0.125]
        if ids: out += [1000 + i]
        return out

    tc = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I", "float": "f",
          "double": "d", "int8": "b", "uint8": "B", "int16": "h", "uint16": "H", "int32": "i", "uint32": "I",
          "float32": "f", "float64": "d"}
    if fmt == "ascii":
        body = "".join(" ".join(f"{x:.6g}" if isinstance(x, float) else str(x) for x in values(i, p)) + "\n"
                       for i, p in enumerate(v))
        if extra: body += "3 0.5 1 2 7\n0 -3\n"
        body += "".join(f"{len(t)} " + " ".join(map(str, t)) + "\n" for t in f)
        return h + body
    e = "<" if fmt == "binary_little_endian" else ">"
    types = [t for t, _ in props]
    body = b"".join(b"".join(struct.pack(e + tc[t], x) for t, x in zip(types, values(i, p))) for i, p in enumerate(v))
    if extra: body += struct.pack(e + "B3fh", 3, 0.5, 1, 2, 7) + struct.pack(e + "Bh", 0, -3)
    for t in f:
        body += struct.pack(e + tc[cnt], len(t)) + b"".join(struct.pack(e + tc[idx], i) for i in t)
    return h.encode() + body


def obj(v, f, style="plain"):
    out = "# fuzz seed\nmtllib none.mtl\no thing\n"
    out += "".join(f"v {a:.6g} {b:.6g} {c:.6g}" + (" 1.0" if style == "w" else "") + "\n" for a, b, c in v)
    if style in ("vt", "vtvn", "vn"):
        out += "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
    out += "g group\ns 1\nusemtl m\n"
    for t in f:
        if style == "vt": c = [f"{i + 1}/{1 + k % 3}" for k, i in enumerate(t)]
        elif style == "vn": c = [f"{i + 1}//1" for i in t]
        elif style == "vtvn": c = [f"{i + 1}/{1 + k % 3}/1" for k, i in enumerate(t)]
        elif style == "negative": c = [str(i - len(v)) for i in t]
        else: c = [str(i + 1) for i in t]
        out += "f " + " ".join(c) + "\n"
    return out


def main():
    for kind in ("ply", "obj"):
        shutil.rmtree(os.path.join(SEEDS, kind), ignore_errors=True)
    sv, sf = uv_sphere()
    put("ply", "sphere_ascii.ply", ply("ascii", sv, sf, ids=True, color=True, normal=True))
    put("ply", "sphere_le.ply", ply("binary_little_endian", sv, sf, ids=True, vel=True))
    put("ply", "sphere_be.ply", ply("binary_big_endian", sv, sf, color=True, idx="uint", cnt="int", pos="double"))
    put("ply", "cube_quads_ascii.ply", ply("ascii", CUBE_V, CUBE_Q, extra=True))
    put("ply", "cube_quads_le.ply", ply("binary_little_endian", CUBE_V, CUBE_Q, extra=True, idx="ushort"))
    put("ply", "cube_quads_be.ply", ply("binary_big_endian", CUBE_V, CUBE_Q, ids=True, idx="uint8", cnt="uint16"))
    put("obj", "sphere.obj", obj(sv, sf))
    put("obj", "sphere_w.obj", obj(sv, sf, "w"))
    put("obj", "cube_quads_vt.obj", obj(CUBE_V, CUBE_Q, "vt"))
    put("obj", "cube_quads_vn.obj", obj(CUBE_V, CUBE_Q, "vn"))
    put("obj", "cube_quads_vtvn.obj", obj(CUBE_V, CUBE_Q, "vtvn"))
    put("obj", "sphere_negative.obj", obj(sv, sf, "negative"))
    put("obj", "crlf.obj", obj(CUBE_V, CUBE_Q).replace("\n", "\r\n"))


if __name__ == "__main__":
    main()
