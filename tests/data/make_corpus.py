#!/usr/bin/env python3
"""Regenerates the small test inputs of tests/data (committed; run only to change them):
bad/       malformed or degenerate mesh files, one fault each (expected outcomes in tests/tools/CMakeLists.txt)
sequences/ tiny frame folders (duplicate numbers, a gap, no frames; open_holes: a moving sphere with holes for
           `track --close-holes`)
events/    event-list files (docs/formats.md) for `topotrack events`
"""
import os
import random
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
BAD = os.path.join(HERE, "bad")

OCTA_V = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCTA_F = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def put(folder, name, data):
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def ply_header(fmt, nv, nf, vprops="property float x\nproperty float y\nproperty float z\n",
               fprops="property list uchar int vertex_indices\n"):
    return (f"ply\nformat {fmt} 1.0\nelement vertex {nv}\n{vprops}element face {nf}\n{fprops}end_header\n")


def ascii_ply(verts=OCTA_V, faces=OCTA_F, nv=None, nf=None, tail=""):
    body = "".join(" ".join(str(c) for c in v) + "\n" for v in verts)
    body += "".join(f"{len(f)} " + " ".join(str(i) for i in f) + "\n" for f in faces)
    return ply_header("ascii", len(verts) if nv is None else nv, len(faces) if nf is None else nf) + body + tail


def binary_ply(verts=OCTA_V, faces=OCTA_F, nv=None, nf=None, index_fmt="<i", count_fmt="<B"):
    body = b"".join(struct.pack("<3f", *v) for v in verts)
    for f in faces:
        body += struct.pack(count_fmt, len(f)) + b"".join(struct.pack(index_fmt, i) for i in f)
    return ply_header("binary_little_endian", len(verts) if nv is None else nv,
                      len(faces) if nf is None else nf).encode() + body


def obj(verts=OCTA_V, faces=OCTA_F, extra=""):
    return ("".join(f"v {v[0]} {v[1]} {v[2]}\n" for v in verts) +
            "".join("f " + " ".join(str(i + 1) for i in f) + "\n" for f in faces) + extra)


def main():
    rnd = random.Random(2012)
    # PLY header faults
    put(BAD, "empty.ply", b"")
    put(BAD, "not_ply_magic.ply", ascii_ply().replace("ply\n", "plx\n", 1))
    put(BAD, "no_format.ply", ascii_ply().replace("format ascii 1.0\n", ""))
    put(BAD, "unknown_format.ply", ascii_ply().replace("format ascii", "format binary_middle_endian"))
    put(BAD, "unknown_type.ply", ascii_ply().replace("property float x", "property float128 x"))
    put(BAD, "no_end_header.ply", ascii_ply().split("end_header")[0])
    put(BAD, "bad_element_count.ply", ascii_ply().replace("element vertex 6", "element vertex -6"))
    put(BAD, "missing_z.ply", ascii_ply().replace("property float z\n", "property float w\n"))
    put(BAD, "no_vertex_indices.ply", ascii_ply().replace("vertex_indices", "corners"))
    put(BAD, "zero_vertices.ply", ply_header("ascii", 0, 0))
    put(BAD, "unknown_keyword.ply", ascii_ply().replace("element face", "elemental face"))
    # PLY body faults
    full = binary_ply()
    put(BAD, "truncated_binary.ply", full[: len(full) - 20])
    put(BAD, "lying_vertex_count_binary.ply", binary_ply(nv=1000000))
    put(BAD, "lying_face_count_ascii.ply", ascii_ply(nf=20))
    put(BAD, "trailing_garbage_binary.ply", full + b"\x00\x01\x02")
    put(BAD, "trailing_data_ascii.ply", ascii_ply(tail="3 0 1 2\n"))
    put(BAD, "nan_vertex_ascii.ply", ascii_ply(verts=OCTA_V[:3] + [("nan", 0, 0)] + OCTA_V[4:]))
    put(BAD, "inf_vertex_binary.ply", binary_ply(verts=OCTA_V[:2] + [(float("inf"), 0, 0)] + OCTA_V[3:]))
    put(BAD, "negative_index.ply", ascii_ply(faces=OCTA_F[:3] + [(3, -1, 4)] + OCTA_F[4:]))
    put(BAD, "out_of_range_index.ply", ascii_ply(faces=OCTA_F[:5] + [(1, 2, 6)] + OCTA_F[6:]))
    put(BAD, "huge_index_binary.ply", binary_ply(faces=OCTA_F[:7] + [(0, 3, 2147483647)]))
    put(BAD, "huge_list_count_binary.ply",
        ply_header("binary_little_endian", 6, 1, fprops="property list uint int vertex_indices\n").encode() +
        b"".join(struct.pack("<3f", *v) for v in OCTA_V) + struct.pack("<I", 4000000000) + struct.pack("<3i", 0, 1, 2))
    put(BAD, "garbage_token_ascii.ply", ascii_ply(verts=OCTA_V[:4] + [(0, 0, "zero")] + OCTA_V[5:]))
    put(BAD, "face_two_vertices.ply", ascii_ply(faces=OCTA_F[:2] + [(1, 3)] + OCTA_F[3:]))
    put(BAD, "float_index.ply", ascii_ply().replace("3 0 2 4\n", "3 0 2.5 4\n"))
    put(BAD, "binary_garbage.ply", bytes(rnd.randrange(256) for _ in range(512)))
    put(BAD, "binary_garbage_after_header.ply", ply_header("binary_little_endian", 6, 8).encode() +
        bytes(rnd.randrange(256) for _ in range(6 * 12 + 8 * 13)))
    # OBJ faults
    put(BAD, "empty.obj", b"")
    put(BAD, "obj_garbage_token.obj", obj().replace("v 0 1 0", "v 0 one 0"))
    put(BAD, "obj_nan.obj", obj().replace("v 0 -1 0", "v 0 -1 nan"))
    put(BAD, "obj_inf.obj", obj().replace("v 0 -1 0", "v 0 -inf 0"))
    put(BAD, "obj_index_zero.obj", obj().replace("f 1 3 5", "f 0 3 5"))
    put(BAD, "obj_index_out_of_range.obj", obj().replace("f 1 3 5", "f 1 3 7"))
    put(BAD, "obj_negative_out_of_range.obj", obj().replace("f 1 3 5", "f 1 3 -7"))
    put(BAD, "obj_huge_index.obj", obj().replace("f 1 3 5", "f 1 3 99999999999999999999"))
    put(BAD, "obj_face_two_vertices.obj", obj().replace("f 1 3 5", "f 1 3"))
    put(BAD, "obj_two_coordinates.obj", obj().replace("v 0 0 1", "v 0 0"))
    put(BAD, "obj_no_vertices.obj", "# nothing but a comment\ng empty\n")
    put(BAD, "obj_bad_corner.obj", obj().replace("f 1 3 5", "f 1 3/1/1/1 5"))
    # found by tests/fuzz/fuzz_obj: -2^63 as a relative index (its negation overflowed, and the index was kept)
    put(BAD, "obj_int64_min_index.obj", "v 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 -9223372036854775808\n")
    put(BAD, "obj_binary_garbage.obj", b"v " + bytes(rnd.randrange(256) for _ in range(512)))
    # Other files
    put(BAD, "unknown_extension.stl", "solid s\nendsolid s\n")
    put(BAD, "no_extension", ascii_ply())
    # Readable but not a closed 2-manifold: `info` reports, commands needing closed input reject
    put(BAD, "open_surface.ply", ascii_ply(faces=OCTA_F[:-1]))
    fin_v = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)]
    put(BAD, "non_manifold_edge.obj", obj(fin_v, [(0, 1, 2), (1, 0, 3), (0, 1, 4)]))
    tet = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    tet_f = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    put(BAD, "non_manifold_vertex.obj", obj(tet + [(-1, 0, 0), (0, -1, 0), (0, 0, -1)],
                                           tet_f + [(0, 4, 5), (0, 6, 4), (0, 5, 6), (4, 6, 5)]))
    flipped = list(OCTA_F)
    flipped[3] = (0, 3, 4)
    put(BAD, "inconsistent_orientation.obj", obj(faces=flipped))
    put(BAD, "degenerate_triangles.obj", obj(OCTA_V + [(2, 2, 2)], OCTA_F + [(0, 0, 1), (6, 6, 6)]))
    put(BAD, "collinear_triangle.ply", ascii_ply(OCTA_V + [(5, 0, 0), (6, 0, 0), (7, 0, 0)], OCTA_F + [(6, 7, 8)]))

    # Sequences
    seq = os.path.join(HERE, "sequences")
    put(os.path.join(seq, "duplicate"), "a.0001.ply", ascii_ply())
    put(os.path.join(seq, "duplicate"), "a.0001.obj", obj())
    put(os.path.join(seq, "duplicate"), "a.0002.ply", ascii_ply())
    for n in (1, 2, 4):
        put(os.path.join(seq, "gap"), f"g.{n:04d}.ply", ascii_ply())
    put(os.path.join(seq, "no_frames"), "README.txt", "A folder without mesh files.\n")

    # Event files: split(1,2 -> 7, 0.25), collapse(7,2 -> 9), patch_create (boundary 1 3 4; 20 <- .5*1+.25*3+.25*4,
    # 21 <- .5*20 + .5*4)
    events = [
        (1, [1, 2], [1, 2, 7], [(7, [(1, 0.25), (2, 0.75)])], []),
        (3, [7, 2], [9], [(9, [(7, 0.5), (2, 0.5)])], [(7, [(9, 1.0)]), (2, [(9, 1.0)])]),
        (4, [1, 3, 4], [1, 3, 4, 20, 21], [(20, [(1, 0.5), (3, 0.25), (4, 0.25)]), (21, [(20, 0.5), (4, 0.5)])], []),
    ]
    n_ids = sum(len(e[1]) + len(e[2]) for e in events)
    rules = [r for e in events for r in e[3] + e[4]]
    body = b"TTEVENTS" + struct.pack("<IIQQQQ", 1, 0, len(events), n_ids, len(rules), sum(len(r[1]) for r in rules))
    for kind, vin, vout, fwd, bwd in events:
        body += struct.pack("<BIIII", kind, len(vin), len(vout), len(fwd), len(bwd))
        body += b"".join(struct.pack("<Q", v) for v in vin + vout)
        for target, terms in fwd + bwd:
            body += struct.pack("<QI", target, len(terms)) + b"".join(struct.pack("<Qd", s, w) for s, w in terms)
    h = 0xcbf29ce484222325
    for c in body:
        h = ((h ^ c) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    good = body + struct.pack("<Q", h)
    ev = os.path.join(HERE, "events")
    put(ev, "sample.events", good)
    put(ev, "truncated.events", good[:-9])
    put(ev, "bad_magic.events", b"TTEVENTX" + good[8:])
    put(ev, "flipped_byte.events", good[:100] + bytes([good[100] ^ 0x10]) + good[101:])
    put(ev, "empty.events", b"")

    open_holes_sequence(os.path.join(HERE, "sequences", "open_holes"))


def open_holes_sequence(folder):
    """A sphere of radius 0.5 moving along x, 3 frames, each with holes (triangles removed around one or two
    directions, each hole about 0.2 across): `track` rejects frame 1, `track --close-holes` tracks it."""
    import math
    rings, sectors = 16, 32
    for frame, holes in ((1, [(1, 0, 0)]), (2, [(0, 1, 0), (0, 0, -1)]), (3, [(-0.6, 0.8, 0)])):
        c = (0.05 * (frame - 1), 0.0, 0.0)
        v = [(0.0, 0.0, 1.0)]
        for r in range(1, rings):
            th = math.pi * r / rings
            v += [(math.sin(th) * math.cos(2 * math.pi * s / sectors), math.sin(th) * math.sin(2 * math.pi * s / sectors),
                   math.cos(th)) for s in range(sectors)]
        v.append((0.0, 0.0, -1.0))
        ring = lambda r, s: 1 + (r - 1) * sectors + s % sectors
        f = []
        for s in range(sectors):
            f += [(0, ring(1, s), ring(1, s + 1)), (len(v) - 1, ring(rings - 1, s + 1), ring(rings - 1, s))]
        for r in range(1, rings - 1):
            for s in range(sectors):
                a, b, cc, d = ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1)
                f += [(a, cc, b), (b, cc, d)]
        def near_hole(t):
            m = [sum(v[i][k] for i in t) / 3 for k in range(3)]
            return any(sum(m[k] * h[k] for k in range(3)) / math.sqrt(sum(x * x for x in h)) > 0.95 for h in holes)
        f = [t for t in f if not near_hole(t)]
        verts = [(0.5 * x + c[0], 0.5 * y + c[1], 0.5 * z + c[2]) for x, y, z in v]
        body = b"".join(struct.pack("<3f", *p) for p in verts)
        body += b"".join(struct.pack("<B3i", 3, *t) for t in f)
        put(folder, f"sphere.{frame:04d}.ply", ply_header("binary_little_endian", len(verts), len(f)).encode() + body)


if __name__ == "__main__":
    main()
