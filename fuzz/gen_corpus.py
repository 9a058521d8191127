#!/usr/bin/env python3
"""fuzz/gen_corpus.py: (re)generate the seed corpora in fuzz/corpus/.

    python3 fuzz/gen_corpus.py [CONFORMANCE_DIR]   (default /work/shared/conformance)

Seeds come from the conformance inputs (PostGIS, GEOS and delaunator cases)
and from hand-made edge cases.  Formats:

  fuzz_core         see fuzz/fuzz_core.c (mode, options, grid, tolerance, data)
  fuzz_gserialized  a PostGIS GSERIALIZED value without its 4-byte varlena
                    header (the harness adds it), written by gser() below
  fuzz_state        fuzz/fuzz_state.c: uint16 split, then one or two serialized
                    ST_TDCDelaunay states (without varlena headers), or of
                    ST_TDCContours, ST_TDCDrape or ST_TDCInterpolate (their
                    magic numbers pick fuzz/fuzz_state_tin.c)

The output is deterministic; files are named by content hash.
"""
import hashlib
import json
import math
import os
import re
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
CONF = sys.argv[1] if len(sys.argv) > 1 else "/work/shared/conformance"
OUT = os.path.join(HERE, "corpus")


def put(target, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    name = hashlib.sha1(data).hexdigest()[:16]
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def known(name, target, data):
    """A fixture of fuzz/known/ (see its README), also a seed of target."""
    put(target, data)
    with open(os.path.join(HERE, "known", name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- WKT parser
TOK = re.compile(r"\s*([A-Za-z]+|\(|\)|,|[-+0-9.eE]+|nan|inf)")


def tokens(s):
    pos = 0
    out = []
    while pos < len(s):
        m = TOK.match(s, pos)
        if not m:
            if s[pos:].strip() == "":
                break
            raise ValueError("bad WKT at %r" % s[pos:pos + 20])
        out.append(m.group(1))
        pos = m.end()
    return out


def parse_wkt(s):
    """Returns (type, dims, payload): payload nested lists of vertex tuples."""
    t = tokens(s)
    i = [0]

    def peek():
        return t[i[0]].upper() if i[0] < len(t) else None

    def take():
        i[0] += 1
        return t[i[0] - 1]

    def coords():
        v = []
        while peek() not in (",", ")"):
            v.append(float(take()))
        return tuple(v)

    def ptlist():
        take()  # (
        pts = []
        while True:
            pts.append(coords())
            if take() == ")":
                return pts

    def body(typ):
        if peek() == "EMPTY":
            take()
            return (typ, None, [])
        if typ == "POINT":
            take()
            c = coords()
            take()
            return (typ, len(c), [c])
        if typ == "LINESTRING":
            pts = ptlist()
            return (typ, len(pts[0]), pts)
        if typ in ("POLYGON", "TRIANGLE"):
            take()
            rings = []
            while True:
                rings.append(ptlist())
                if take() == ")":
                    break
            if typ == "TRIANGLE":
                return (typ, len(rings[0][0]), rings[0])
            return (typ, len(rings[0][0]), rings)
        if typ == "MULTIPOINT":
            take()
            parts = []
            while True:
                if peek() == "(":
                    take()
                    c = coords()
                    take()
                else:
                    c = coords()
                parts.append(("POINT", len(c), [c]))
                if take() == ")":
                    break
            return (typ, parts[0][1], parts)
        sub = {"MULTILINESTRING": "LINESTRING", "MULTIPOLYGON": "POLYGON",
               "TIN": "TRIANGLE", "POLYHEDRALSURFACE": "POLYGON"}.get(typ)
        if sub is None and typ != "GEOMETRYCOLLECTION":
            raise ValueError("unsupported type " + typ)
        take()
        parts = []
        while True:
            parts.append(body(sub) if sub else tagged())
            if take() == ")":
                break
        d = next((p[1] for p in parts if p[1]), 2)
        return (typ, d, parts)

    def tagged():
        typ = take().upper()
        if peek() in ("Z", "M", "ZM"):
            take()
        return body(typ)

    return tagged()


TYPES = {"POINT": 1, "LINESTRING": 2, "POLYGON": 3, "MULTIPOINT": 4,
         "MULTILINESTRING": 5, "MULTIPOLYGON": 6, "GEOMETRYCOLLECTION": 7,
         "POLYHEDRALSURFACE": 13, "TRIANGLE": 14, "TIN": 15}


def body(g, nd):
    typ, _, pl = g
    out = struct.pack("<II", TYPES[typ], len(pl) if typ != "TRIANGLE" else len(pl))
    if typ in ("POINT", "LINESTRING", "TRIANGLE"):
        for c in pl:
            out += struct.pack("<%dd" % nd, *(list(c) + [0.0] * nd)[:nd])
    elif typ == "POLYGON":
        for r in pl:
            out += struct.pack("<I", len(r))
        if len(pl) % 2:
            out += b"\0\0\0\0"
        for r in pl:
            for c in r:
                out += struct.pack("<%dd" % nd, *(list(c) + [0.0] * nd)[:nd])
    else:
        for p in pl:
            out += body(p, nd)
    return out


def gser(g, srid=0, z=False, m=False, bbox=None, version=2):
    nd = 2 + z + m
    flags = (1 if z else 0) | (2 if m else 0) | (0x40 if version == 2 else 0)
    if bbox is not None:
        flags |= 4
    s = srid & 0x1FFFFF
    out = bytes([(s >> 16) & 0x1F, (s >> 8) & 0xFF, s & 0xFF, flags])
    if bbox is not None:
        out += struct.pack("<%df" % len(bbox), *bbox)
    return out + body(g, nd)


def all_coords(g):
    typ, _, pl = g
    if typ in ("POINT", "LINESTRING", "TRIANGLE"):
        return list(pl)
    if typ == "POLYGON":
        return [c for r in pl for c in r]
    return [c for p in pl for c in all_coords(p)]


# ---------------------------------------------------------------- inputs
def conformance_wkts():
    wkts = []
    for fn in ("postgis-cases.txt", "geos-cases.txt"):
        p = os.path.join(CONF, fn)
        if not os.path.exists(p):
            continue
        for line in open(p, encoding="utf-8", errors="replace"):
            m = re.match(r"\s*input:\s*'?([A-Z][A-Z ]*\s*\(.*?\)|[A-Z]+ EMPTY)'?(\s|$)", line)
            if not m:
                continue
            w = m.group(1)
            # balance the parentheses of the greedy-free match
            depth = 0
            for k, ch in enumerate(line[line.index(w):]):
                depth += ch == "("
                depth -= ch == ")"
                if depth == 0 and ch == ")":
                    w = line[line.index(w):line.index(w) + k + 1]
                    break
            try:
                wkts.append((w, parse_wkt(w)))
            except (ValueError, IndexError, struct.error):
                pass
    return wkts


def delaunator_sets():
    d = os.path.join(CONF, "delaunator")
    out = []
    if os.path.isdir(d):
        for fn in sorted(os.listdir(d)):
            pts = json.load(open(os.path.join(d, fn)))
            out.append((fn, [tuple(map(float, p[:2])) for p in pts]))
    return out


def core(mode, opt, grid, tol, data):
    return bytes([mode, opt, grid, tol]) + data


def raw_pairs(pts):
    return b"".join(struct.pack("<dd", x, y) for x, y in pts)


def main():
    wkts = conformance_wkts()
    dl = delaunator_sets()

    # ---- fuzz_core
    for k, (w, g) in enumerate(wkts):
        pts = [c[:2] for c in all_coords(g)]
        if pts:
            put("fuzz_core", core(0, (k % 4) | ((k % 6) << 2) | (0x20 if k % 3 == 0 else 0),
                                  (k * 7) % 65, 0, raw_pairs(pts[:1024])))
    for k, (fn, pts) in enumerate(dl):
        put("fuzz_core", core(0, 0x20 | (k % 4) | (((k + 2) % 6) << 2), 0, 0, raw_pairs(pts[:1000])))
    # small integers, collinear, magnitudes, palette, ulps, float32, circle, expanded
    put("fuzz_core", core(1, 0x21, 0, 0, bytes(range(256))))
    put("fuzz_core", core(1, 0x2f, 3, 0, bytes([0, 1, 16, 17, 0, 1, 255, 34])))
    put("fuzz_core", core(2, 0x25, 0, 0, bytes([5, 6, 0, 0, 0]) + bytes(range(0, 200, 3))))
    put("fuzz_core", core(2, 0x25, 0, 0, bytes([5, 6, 9, 0, 0]) + bytes(range(0, 200, 3))))
    put("fuzz_core", core(2, 0x33, 4, 0, bytes([4, 4, 0, 0, 0]) + bytes(range(0, 50))))
    put("fuzz_core", core(3, 0x2a, 0, 0, bytes([119, 0x85]) + os.urandom(0) + bytes(range(120))))
    put("fuzz_core", core(3, 0x2a, 0, 0, bytes([0, 0x7f]) + bytes(range(120))))
    put("fuzz_core", core(4, 0x26, 0, 0, bytes([0, 1, 2, 3, 4, 5, 6, 7] * 5)))
    put("fuzz_core", core(4, 0x20, 0, 0, bytes([0, 5, 0, 5, 1, 2])))
    put("fuzz_core", core(5, 0x2e, 2, 0, bytes(range(256))))
    put("fuzz_core", core(6, 0x21, 0, 0, struct.pack("<8f", 0, 0, 1, 0, 0, 1, 3.4e38, -3.4e38)))
    put("fuzz_core", core(7, 0x2d, 0, 0, bytes([0, 0]) + bytes(range(0, 100))))
    put("fuzz_core", core(7, 0x29, 0, 0, bytes([3, 250]) + bytes(range(0, 120, 2)) + bytes([255])))
    for kind in range(3):
        put("fuzz_core", core(8, 0x20 | kind, 0, 0, bytes([kind]) + struct.pack("<HQ", 5000, 42 + kind)))
    put("fuzz_core", core(8, 0x01, 0, 0, bytes([0x81]) + struct.pack("<HQ", 25000, 45)))
    put("fuzz_core", core(8, 0x1b, 0, 0, bytes([0]) + struct.pack("<HQ", 3000, 7) + bytes(range(60))))
    # tolerance
    put("fuzz_core", core(1, 0x25, 0, 2, bytes(range(0, 256, 5))))
    put("fuzz_core", core(0, 0x21, 0, 5 | 0x70, raw_pairs([(0, 0), (1, 0), (0, 1), (1e-3, 1e-3), (5, 5)])))
    # invalid: NaN, Inf, too large, too small, bad options
    put("fuzz_core", core(0, 0x00, 0, 0, raw_pairs([(0, 0), (1, 0), (float("nan"), 1)])))
    put("fuzz_core", core(0, 0x00, 0, 0, raw_pairs([(0, 0), (1, float("inf")), (0, 1)])))
    put("fuzz_core", core(0, 0x00, 0, 0, raw_pairs([(0, 0), (1e61, 0), (0, 1)])))
    put("fuzz_core", core(0, 0x00, 0, 0, raw_pairs([(0, 0), (1e-61, 0), (0, 1)])))
    put("fuzz_core", core(0, 0x01, 0, 0, raw_pairs([(-1e60, -1e60), (1e60, -1e60), (0, 1e60), (1e-60, 0), (-0.0, 0)])))
    for b in range(8):
        put("fuzz_core", core(1, 0x40, 0, b << 5, bytes(range(10))))

    # ---- fuzz_gserialized
    for k, (w, g) in enumerate(wkts):
        z = g[1] == 3 and "Z" in w.upper().split("(")[0]
        try:
            put("fuzz_gserialized", gser(g, srid=4326 if k % 2 else 0, z=z,
                                         bbox=[0, 1, 0, 1] + ([0, 1] if z else []) if k % 3 == 0 else None))
        except struct.error:
            pass
    for fn, pts in dl[:4]:
        put("fuzz_gserialized", gser(("MULTIPOINT", 2, [("POINT", 2, [p]) for p in pts[:200]])))
    hand = [
        "POINT EMPTY", "GEOMETRYCOLLECTION EMPTY", "POINT(1 2)",
        "LINESTRING(0 0,1 1,2 0)", "POLYGON((0 0,4 0,4 4,0 4,0 0),(1 1,2 1,2 2,1 1))",
        "POLYGON((0 0,1 0,0 1,0 0))",
        "MULTIPOLYGON(((0 0,1 0,0 1,0 0)),((5 5,6 5,5 6,5 5),(5.1 5.1,5.2 5.1,5.1 5.2,5.1 5.1)))",
        "GEOMETRYCOLLECTION(POINT(0 0),GEOMETRYCOLLECTION(LINESTRING(1 1,2 2),POINT EMPTY),MULTIPOINT((3 3)))",
        "TIN(((0 0,1 0,0 1,0 0)),((1 0,1 1,0 1,1 0)))",
        "POLYHEDRALSURFACE(((0 0,1 0,0 1,0 0)))",
        "TRIANGLE((0 0,1 0,0 1,0 0))",
        "MULTILINESTRING((0 0,1 1),EMPTY_PLACEHOLDER)".replace(",EMPTY_PLACEHOLDER", ""),
    ]
    for w in hand:
        g = parse_wkt(w)
        put("fuzz_gserialized", gser(g))
        put("fuzz_gserialized", gser(g, version=1, srid=-1))
    g = parse_wkt("MULTIPOINT(0 0 1,1 0 2,0 1 3)")
    put("fuzz_gserialized", gser(g, z=True, srid=3857))
    put("fuzz_gserialized", gser(parse_wkt("MULTIPOINT(0 0 1 7,1 0 2 7,0 1 3 7)"), z=True, m=True,
                                 bbox=[0, 1, 0, 1, 1, 3, 7, 7]))
    put("fuzz_gserialized", gser(parse_wkt("MULTIPOINT(0 0 7,1 0 7,0 1 7)"), m=True))
    # geodetic bbox, extended flags
    b = bytearray(gser(parse_wkt("POINT(1 2)")))
    put("fuzz_gserialized", bytes(b[:3]) + bytes([0x40 | 0x04 | 0x08]) + struct.pack("<6f", *[0] * 6) + bytes(b[4:]))
    put("fuzz_gserialized", bytes(b[:3]) + bytes([0x40 | 0x10]) + b"\0" * 8 + bytes(b[4:]))
    # curves (the harness refuses, reads or strokes them by the input's
    # length modulo 3: these are 60, 12, 124 and 68 bytes), unknown type,
    # NaN, truncation
    arc = struct.pack("<II6d", 8, 3, 0, 0, 1, 1, 2, 0)
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + arc)
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II", 9, 0))
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II", 11, 2) + arc + arc)
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II", 9, 1) + arc)
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II", 99, 0))
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II2d", 1, 1, float("nan"), 0))
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II2d", 2, 5, 0, 0))
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<II", 7, 0xFFFFFFFF))
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + struct.pack("<III", 3, 3, 1))
    nest = b""
    for _ in range(40):
        nest += struct.pack("<II", 7, 1)
    put("fuzz_gserialized", bytes([0, 0, 0, 0x40]) + nest + struct.pack("<II2d", 1, 1, 3, 4))

    # ---- fuzz_state
    def state(have_first=True, hasz=False, params=True, srid=0, flags=0, tol=0.0, pts=(), zs=None,
              magic=0x41434454, version=1, pad=0, n=None):
        bits = (1 if have_first else 0) | (2 if hasz else 0) | (4 if params else 0)
        n = len(pts) if n is None else n
        out = struct.pack("<IIIiiIdQ", magic, version, bits, srid, flags, pad, tol, n)
        out += b"".join(struct.pack("<dd", *p) for p in pts)
        if hasz:
            out += b"".join(struct.pack("<d", z) for z in (zs or [0.0] * len(pts)))
        return out

    def st2(a, b=b""):
        return struct.pack("<H", len(a)) + a + b

    sq = [(0, 0), (1, 0), (0, 1), (1, 1)]
    put("fuzz_state", st2(state(pts=sq)))
    put("fuzz_state", st2(state(pts=sq), state(pts=[(5, 5), (6, 6)])))
    put("fuzz_state", st2(state(pts=sq, hasz=True, zs=[1, 2, 3, 4], srid=4326),
                          state(pts=[(5, 5)], hasz=True, srid=4326)))
    put("fuzz_state", st2(state(pts=sq, srid=4326), state(pts=sq, srid=3857)))
    put("fuzz_state", st2(state(pts=sq), state(pts=sq, hasz=True)))
    put("fuzz_state", st2(state(pts=sq, flags=1, tol=0.5), state(pts=sq, flags=2, tol=0.5)))
    put("fuzz_state", st2(state(have_first=False, params=False, pts=[])))
    put("fuzz_state", st2(state(have_first=False, params=True, pts=[]), state(pts=sq)))
    put("fuzz_state", st2(state(pts=sq, magic=0)))
    put("fuzz_state", st2(state(pts=sq, version=2)))
    put("fuzz_state", st2(state(pts=sq, pad=1)))
    put("fuzz_state", st2(state(pts=sq, n=5)))
    put("fuzz_state", st2(state(pts=sq, n=(1 << 64) - 1)))
    put("fuzz_state", st2(state(pts=sq, n=(1 << 60))))
    put("fuzz_state", st2(state(pts=[(float("nan"), 0)])))
    put("fuzz_state", st2(state(pts=sq, flags=7)))
    put("fuzz_state", st2(state(pts=sq, tol=-1.0)))
    put("fuzz_state", st2(state(pts=sq, tol=float("inf"))))
    put("fuzz_state", st2(state(pts=sq)[:30]))
    for fn, pts in dl[:3]:
        put("fuzz_state", st2(state(pts=pts[:200])))

    # ---- fuzz_state: the TIN aggregates (fuzz/fuzz_state_tin.c), the
    # first state's magic picking the aggregate.  The vertex part as above,
    # with heights, then the aggregate's own part (ST_TDCDrape's and
    # ST_TDCInterpolate's at version 2: the breaklines' segments last).
    TCN, TDR, TRI = 0x314E4354, 0x31524454, 0x31495254
    VERSION = {TCN: 2, TDR: 2, TRI: 2}
    sqz = [1.0, 2.0, 3.0, 4.5]

    def samples(magic, pts=sq, zs=sqz, srid=4326, have_first=True, hasz=True, params=False, n=None,
                version=None):
        # no first value: no dimensions either (else the state is corrupt)
        return state(magic=magic, have_first=have_first, hasz=hasz and have_first, params=params,
                     srid=srid,
                     pts=pts if have_first else [], zs=zs, n=n,
                     version=VERSION[magic] if version is None else version)

    def contour(ps=1, interval=10.0, base=0.0, rows=4, zero=0, max_edge=0.0):
        return struct.pack("<IIddqd", ps, zero, interval, base, rows, max_edge)

    def varlena(b):
        return struct.pack("<I", (len(b) + 4) << 2) + b

    line = varlena(gser(parse_wkt("LINESTRING(0.25 0.25,0.75 0.5,0.5 0.9)"), srid=4326))

    def segs(pairs):
        return b"".join(struct.pack("<II", a, b) for a, b in pairs)

    def drape(ps=1, method=b"linear", target=line, rows=4, ml=None, tl=None, seg=b""):
        if not ps:
            method, target = b"", b""
        return struct.pack("<IIQq", ps, len(method) if ml is None else ml,
                           len(target) if tl is None else tl, rows) + method + target + seg

    def interp(ps=1, method=b"linear", rows=4, band=1, srid=4326, w=10, h=8,
               gt=(0.0, 0.125, 0.0, 1.0, 0.0, -0.125), pixtype=11, hasnodata=1, nodata=-9999.0,
               seg=b""):
        if not ps:
            method = b""
        return struct.pack("<IIqiiII6diId", ps, len(method), rows, band, srid, w, h,
                           *gt, pixtype, hasnodata, nodata) + method + seg

    far = [(5, 5), (6, 5)]
    farz = [7.0, 8.0]
    for magic, ext, kname in ((TCN, contour, "contours"), (TDR, drape, "drape"),
                              (TRI, interp, "interpolate")):
        a = samples(magic) + ext()
        put("fuzz_state", st2(a))
        put("fuzz_state", st2(a, samples(magic, pts=far, zs=farz) + ext(rows=2)))
        # no parameters: nothing in the state
        put("fuzz_state", st2(samples(magic, have_first=False) + ext(ps=0, rows=0), a))
        put("fuzz_state", st2(a, samples(magic, have_first=False) + ext(ps=0, rows=0)))
        # no parameters but samples: combine would drop them
        known("state_unset_with_samples_" + kname, "fuzz_state",
              st2(a, samples(magic, pts=far, zs=farz) + ext(ps=0, rows=2)))
        put("fuzz_state", st2(samples(magic) + ext(ps=0, rows=4), a))
        # mixed SRIDs, dimensions; samples without Z; truncated; the
        # Delaunay part's parameters (which the TIN aggregates never set)
        put("fuzz_state", st2(a, samples(magic, pts=far, zs=farz, srid=3857) + ext(rows=2)))
        put("fuzz_state", st2(a, samples(magic, pts=[], zs=[], hasz=False) + ext(rows=1)))
        put("fuzz_state", st2(samples(magic, hasz=False) + ext()))
        put("fuzz_state", st2(a[:-3]))
        put("fuzz_state", st2(samples(magic, params=True) + ext(), a))
        # rows at the limits: the sum overflows int64
        big = samples(magic) + ext(rows=(1 << 63) - 1)
        known("state_rows_overflow_" + kname, "fuzz_state",
              st2(big, samples(magic, pts=far, zs=farz) + ext(rows=2)))
        put("fuzz_state", st2(samples(magic) + ext(rows=-1)))
        # another version of the format
        put("fuzz_state", st2(samples(magic, version=VERSION[magic] % 2 + 1) + ext()))
    put("fuzz_state", st2(samples(TCN) + contour(), samples(TCN, pts=far, zs=farz) + contour(interval=5.0)))
    put("fuzz_state", st2(samples(TCN) + contour(), samples(TCN, pts=far, zs=farz) + contour(base=-0.0)))
    put("fuzz_state", st2(samples(TCN, have_first=False) + contour(ps=0, interval=float("nan"), rows=0)))
    put("fuzz_state", st2(samples(TCN) + contour(interval=0.0)))
    put("fuzz_state", st2(samples(TCN) + contour(interval=float("inf"))))
    put("fuzz_state", st2(samples(TCN) + contour(base=float("nan"))))
    put("fuzz_state", st2(samples(TCN) + contour(zero=1)))
    # max_edge (version 2): a length, the same in both states, or corrupt
    put("fuzz_state", st2(samples(TCN) + contour(max_edge=1.5),
                          samples(TCN, pts=far, zs=farz) + contour(max_edge=1.5)))
    put("fuzz_state", st2(samples(TCN) + contour(max_edge=1.5),
                          samples(TCN, pts=far, zs=farz) + contour(max_edge=2.0)))
    put("fuzz_state", st2(samples(TCN) + contour(max_edge=-1.0)))
    put("fuzz_state", st2(samples(TCN) + contour(max_edge=float("nan"))))
    put("fuzz_state", st2(samples(TCN) + contour(max_edge=float("inf"))))
    put("fuzz_state", st2(samples(TCN) + contour() + b"\0"))
    put("fuzz_state", st2(samples(TDR) + drape(method=b"nearest"),
                          samples(TDR, pts=far, zs=farz) + drape(method=b"natural_neighbor")))
    put("fuzz_state", st2(samples(TDR) + drape(), samples(TDR, pts=far, zs=farz) + drape(
        target=varlena(gser(parse_wkt("POINT(0.5 0.5)"), srid=4326)))))
    put("fuzz_state", st2(samples(TDR) + drape(method=b"linear:radius=0")))
    put("fuzz_state", st2(samples(TDR) + drape(method=b"cubic")))
    put("fuzz_state", st2(samples(TDR) + drape(method=b"lin\0ar")))
    put("fuzz_state", st2(samples(TDR) + drape(method=b"x" * 65)))
    put("fuzz_state", st2(samples(TDR) + drape(target=b"\x01\0\0\0")))
    put("fuzz_state", st2(samples(TDR) + drape(target=struct.pack("<I", 99 << 2) + line[4:])))
    put("fuzz_state", st2(samples(TDR) + drape(tl=(1 << 64) - 1)))
    put("fuzz_state", st2(samples(TDR) + drape(ml=(1 << 32) - 1)))
    # lengths whose sum wraps: 24 + 6 + (2^64 - 6) = 24 bytes
    known("state_drape_target_length_wraps", "fuzz_state",
          st2(samples(TDR) + drape(method=b"", target=b"", ml=6, tl=(1 << 64) - 6)))
    put("fuzz_state", st2(samples(TRI) + interp(method=b"linear:radius=0:nodata=-1"),
                          samples(TRI, pts=far, zs=farz) + interp(method=b"linear:radius=0:nodata=-1")))
    put("fuzz_state", st2(samples(TRI) + interp(), samples(TRI, pts=far, zs=farz) + interp(w=11)))
    put("fuzz_state", st2(samples(TRI) + interp(nodata=float("nan")),
                          samples(TRI, pts=far, zs=farz) + interp(nodata=float("nan"))))
    put("fuzz_state", st2(samples(TRI) + interp(hasnodata=0, nodata=1.0),
                          samples(TRI, pts=far, zs=farz) + interp(hasnodata=0, nodata=2.0)))
    put("fuzz_state", st2(samples(TRI) + interp(), samples(TRI, pts=far, zs=farz) + interp(band=2)))
    put("fuzz_state", st2(samples(TRI, have_first=False) + interp(ps=0, rows=0, gt=(1.0,) * 6, nodata=5.0)))
    put("fuzz_state", st2(samples(TRI) + interp(method=b"nearest:radius1=1:radius2=2")))
    put("fuzz_state", st2(samples(TRI) + interp(method=b"natural_neighbor:radius=2")))
    put("fuzz_state", st2(samples(TRI) + interp(method=b"invdist")))
    for bad in (dict(band=0), dict(w=65536), dict(h=1 << 31), dict(pixtype=12), dict(pixtype=-1),
                dict(hasnodata=2), dict(w=0, h=0)):
        put("fuzz_state", st2(samples(TRI) + interp(**bad)))

    # breaklines (version 2): the segments after the parameters, ends among
    # the state's vertices (4 here, 2 in the far state)
    BRK = b"linear:breaklines=true"
    for ext, brk2 in ((drape, b"linear:BreakLines=TRUE"),
                      (interp, b"linear:radius=0:breaklines=true:nodata=-1")):
        magic = TDR if ext is drape else TRI
        a = samples(magic) + ext(method=BRK, seg=segs([(0, 1), (1, 3), (3, 2)]))
        put("fuzz_state", st2(a))
        # A's segments, then B's shifted by A's 4 vertices
        put("fuzz_state", st2(a, samples(magic, pts=far, zs=farz) + ext(method=BRK, rows=2,
                                                                          seg=segs([(0, 1)]))))
        put("fuzz_state", st2(a, samples(magic, pts=far, zs=farz) + ext(method=BRK, rows=2)))
        put("fuzz_state", st2(samples(magic) + ext(method=BRK),
                              samples(magic, pts=far, zs=farz) + ext(method=BRK, rows=2,
                                                                     seg=segs([(1, 0)]))))
        # a state without parameters first, then one with segments
        put("fuzz_state", st2(samples(magic, have_first=False) + ext(ps=0, rows=0), a))
        put("fuzz_state", st2(a, samples(magic, have_first=False) + ext(ps=0, rows=0)))
        # breaklines against none: the methods differ
        put("fuzz_state", st2(a, samples(magic, pts=far, zs=farz) + ext(rows=2)))
        put("fuzz_state", st2(samples(magic) + ext(method=brk2, seg=segs([(2, 2), (0, 3)]))))
        put("fuzz_state", st2(samples(magic) + ext(method=b"linear:breaklines=false")))
        # a degenerate segment, accepted as the transition function could
        # not write it but the insertion skips it
        put("fuzz_state", st2(samples(magic) + ext(method=BRK, seg=segs([(1, 1)]))))
        # corrupt: an odd number of ends, a part of one, ends beyond the
        # vertices, segments without breaklines, segments and no vertices,
        # segments without parameters
        put("fuzz_state", st2(samples(magic) + ext(method=BRK, seg=segs([(0, 1)]) + struct.pack("<I", 2))))
        put("fuzz_state", st2(samples(magic) + ext(method=BRK, seg=b"\x01\x00")))
        put("fuzz_state", st2(samples(magic) + ext(method=BRK, seg=segs([(0, 4)]))))
        put("fuzz_state", st2(samples(magic) + ext(method=BRK, seg=segs([(0xFFFFFFFF, 0)]))))
        put("fuzz_state", st2(samples(magic) + ext(seg=segs([(0, 1)]))))
        put("fuzz_state", st2(samples(magic) + ext(method=b"linear:breaklines=false",
                                                   seg=segs([(0, 1)]))))
        put("fuzz_state", st2(samples(magic) + ext(method=b"nearest", seg=segs([(0, 1)]))))
        put("fuzz_state", st2(samples(magic, have_first=False) + ext(method=BRK, rows=0,
                                                                     seg=segs([(0, 0)]))))
        put("fuzz_state", st2(samples(magic, have_first=False) + ext(ps=0, rows=0, seg=segs([(0, 0)]))))
        # breaklines are linear's only
        put("fuzz_state", st2(samples(magic) + ext(method=b"nearest:breaklines=true", seg=segs([(0, 1)]))))
        # row counts that overflow, with segments on both sides
        put("fuzz_state", st2(samples(magic) + ext(method=BRK, rows=(1 << 63) - 1, seg=segs([(0, 1)])),
                              samples(magic, pts=far, zs=farz) + ext(method=BRK, rows=2,
                                                                     seg=segs([(0, 1)]))))
    # ST_TDCDrape takes no option but breaklines
    put("fuzz_state", st2(samples(TDR) + drape(method=b"linear:breaklines=true:radius=0",
                                               seg=segs([(0, 1)]))))
    put("fuzz_state", st2(samples(TDR) + drape(method=BRK, target=b"\x01\0\0\0",
                                               seg=segs([(0, 1)]))))



# ---------------------------------------------------------------- rasters
PIXBYTES = [1, 1, 1, 1, 1, 2, 2, 4, 4, 2, 4, 8]
NODATA_FMT = ["B", "B", "B", "b", "B", "h", "H", "i", "I", "e", "f", "d"]


def raster(bands, w=3, h=2, gt=(10.0, 2.0, 0.0, 20.0, 0.0, -2.0), srid=4326,
           version=0, pad_last=True):
    """A PostGIS raster value without its varlena header (the harness adds
    it; alignment counts from the header).  bands: (pixtype, flags, nodata,
    pixels or a path string for an out-of-database band)."""
    out = bytearray(struct.pack("<HH6diHH", version, len(bands), gt[1], gt[5], gt[0],
                                gt[3], gt[2], gt[4], srid, w, h))
    for i, (pt, flags, nd, data) in enumerate(bands):
        pb = PIXBYTES[pt] if pt < 12 else 1
        out += bytes([pt | flags]) + bytes(pb - 1)
        fmt = NODATA_FMT[pt] if pt < 12 else "B"
        out += struct.pack("<" + fmt, nd)
        if isinstance(data, str):
            out += bytes([0]) + data.encode() + b"\0"
        else:
            out += bytes(data)
        if pad_last or i < len(bands) - 1:
            while (len(out) + 4) % 8:
                out += b"\0"
    return bytes(out)


def raster_seeds():
    def rd(band, value):
        put("fuzz_raster", bytes([0, (band + 1) % 8]) + value)

    one = raster([(4, 0x40, 7, range(6))])
    rd(1, one)
    rd(2, one)
    rd(0, one)
    rd(-1, one)
    rd(1, raster([]))
    rd(1, raster([], w=0, h=0))
    rd(1, raster([(4, 0x40, 7, range(6))], version=1))
    rd(1, one[:50])
    rd(1, one[:62])
    rd(1, one[:-3])
    rd(1, raster([(4, 0x40, 7, range(6))], pad_last=False))
    for pt in range(12):
        nd = {9: 1.5, 10: -9999.5, 11: -1e300}.get(pt, 1)
        rd(1, raster([(pt, 0x40 | 0x20, nd, bytes(6 * PIXBYTES[pt]))]))
    rd(1, raster([(12, 0x40, 0, bytes(6))]))
    rd(1, raster([(15, 0, 0, bytes(6))]))
    rd(1, raster([(0, 0x40, 1, bytes(6))])[:64] + bytes([0x40, 0xFF]) + bytes(6) + bytes(4))
    multi = raster([(5, 0x40, -32768, bytes(12)), (11, 0x80 | 0x40, -9999.0, "/data/dem.tif"),
                    (10, 0, 0.0, bytes(24))], gt=(1e6, 0.5, 0.1, 5e6, -0.2, -0.5), srid=32633)
    for b in (1, 2, 3, 4):
        rd(b, multi)
    rd(3, multi[:90])
    rd(3, multi.replace(b"/data/dem.tif\0", b"/data/dem.tif!"))
    big = raster([(11, 0x40, -1.0, bytes(8 * 64 * 64)), (4, 0x40, 0, bytes(64 * 64))], w=64, h=64)
    rd(2, big)

    def wr(pt, w, h, opt, rest):
        put("fuzz_raster", bytes([1, pt, w, h, opt]) + bytes(rest))

    for pt in range(12):
        # nodata index, srid, then value index and mask byte per pixel
        wr(pt, 4, 3, 0, [pt * 5, 0xE6, 0x10, 0, 0] + [b for i in range(12) for b in (i * 7 + pt, i % 3)])
        wr(pt, 2, 2, 2, [17, 0, 0, 0, 0] + list(range(40, 44)))
    wr(11, 5, 5, 1, [0, 1, 0, 0, 0] + [b for i in range(25) for b in (i, i & 1)])
    wr(11, 3, 1, 3, [3, 0, 0, 0, 0, 1, 2, 3])
    wr(4, 2, 2, 0, [0, 0, 0, 0, 0, 1, 0, 2, 0, 3, 0, 4, 0])
    wr(10, 1, 1, 4, [0xFF] + list(struct.pack("<d", -9999.0)) + [0, 0, 0, 0] + [5, 9, 70, 3, 1, 2, 0, 1])
    wr(4, 0, 7, 0, [0, 0, 0, 0, 0])


if __name__ == "__main__":
    main()
    raster_seeds()
