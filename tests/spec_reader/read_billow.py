#!/usr/bin/env python3
r"""Standalone reader/validator for billow asset files (format 1.x).

Written from formats/SPEC.md alone (no Rust sources consulted).  Python 3,
standard library only.

Usage:  read_billow.py FILE.billow [FILE.billow ...]

For each file one line of JSON goes to stdout:
  {"path": ..., "ok": true, "major": 1, "minor": 0, "kind": "Volume", "chunks": [...], ...}
  {"path": ..., "ok": false, "error": "..."}
Exit status 1 if any file failed, else 0.

Validation follows SPEC.md section 7 in order:
  1. magic (first min(8, size) bytes)
  2. size >= 12, major == 1
  3. size >= 32, preamble CRC, kind in {1, 2}, reserved == 0
  4. file_len == actual size, size % 8 == 0
  5. per chunk: header fits, len bound (compared before any arithmetic),
     CRC (zlib.crc32 == CRC-32/ISO-HDLC, section 1), printable tag, known
     element type, reserved == 0, len % elem size == 0, zero padding,
     HEAD first and only there, END last / elem 0 / len 0 / ends at EOF
  6. HEAD payload is UTF-8 RON and satisfies section 6
  7. kind rules: section 8 (Volume, incl. 8.6 LOD bands) or 9 (Cloud)

The RON header (chunk HEAD)
---------------------------
A small but general RON *value* parser is implemented (class RonParser):
structs `(a: v, ...)` optionally with a struct name, tuples `(v, ...)`,
lists `[...]`, maps `{k: v}`, strings with Rust/RON escapes (\" \\ \n \r \t
\0 \' \xHH \u{...} and JSON-style \uXXXX), raw strings r#"..."#, chars,
integers (decimal / 0x / 0o / 0b, `_` separators, sign), floats (incl. inf,
NaN, exponent), booleans, identifiers / unit enum variants, `Some(..)` /
`None`, named tuple/struct variants, `//` and nested `/* */` comments,
trailing commas, and the `#![enable(implicit_some)]` attribute.  Parsing the
whole value (rather than regex-extracting a few fields) is what lets unknown
fields with arbitrary values be ignored robustly (section 5).  The parsed
tree is then checked against the section 6 schema: kind, tool, source,
bounds, colour_space, seed, params, volume (dims, mip_count, texel,
normals, and moments from format 1.4).  Unknown fields are ignored; Option fields may be omitted;
duplicate fields/keys are rejected (the spec is silent; see SPEC_GAPS.md).
"""

import json
import math
import struct
import sys
import zlib
from array import array

MAGIC = b"\x89BLW\r\n\x1a\n"
SUPPORTED_MAJOR = 1
KINDS = {1: "Volume", 2: "Cloud"}

# section 4.2: code -> (name, size)
ELEM_TYPES = {
    0: ("Opaque", 1), 1: ("U8", 1), 2: ("U16", 2), 3: ("U32", 4),
    4: ("F32", 4), 5: ("F16", 2), 6: ("U64", 8), 7: ("F64", 8),
    8: ("I8", 1), 9: ("I16", 2), 10: ("I32", 4), 11: ("I64", 8),
}
E_OPAQUE, E_U8, E_U32, E_F32, E_I8 = 0, 1, 3, 4, 8

F32_MAX = 3.4028234663852886e38
NONE_U32 = 0xFFFFFFFF


class BillowError(Exception):
    pass


def fail(msg):
    raise BillowError(msg)


# ---------------------------------------------------------------- helpers

def le_u32s(buf):
    a = array("I")
    if a.itemsize != 4:  # pragma: no cover - exotic platforms
        return list(struct.unpack("<%dI" % (len(buf) // 4), buf))
    a.frombytes(buf)
    if sys.byteorder != "little":
        a.byteswap()
    return a


def le_f32s(buf):
    a = array("f")
    a.frombytes(buf)
    if sys.byteorder != "little":
        a.byteswap()
    return a


def le_u32_bits(buf):
    return le_u32s(buf)


def first_nonfinite(buf):
    for i, bits in enumerate(le_u32_bits(buf)):
        if bits & 0x7F800000 == 0x7F800000:
            return i
    return -1


def full_mip_count(dims):
    # section 8.2: floor(log2(max(dims))) + 1
    return max(dims).bit_length()


def mip_dims(dims, i):
    return tuple(max(1, d >> i) for d in dims)


def tag_str(tag):
    return tag.decode("latin-1")


def tag_repr(tag):
    # printable tags are shown as-is, others escaped (for error messages)
    if all(0x20 <= b <= 0x7E for b in tag):
        return tag.decode("ascii")
    return "".join(chr(b) if 0x20 <= b <= 0x7E else "\\x%02x" % b for b in tag)


from ron_subset import (  # noqa: E402  (sibling module: the RON value parser)
    RonError,
    RStruct,
    RTuple,
    RIdent,
    RList,
    RMap,
    RStr,
    RInt,
    RFloat,
    RBool,
    RChar,
    RonParser,
)

# --------------------------------------------------------- header schema

class HeaderError(Exception):
    pass


def herr(msg):
    raise HeaderError(msg)


class _Deferred:
    """Section 7 step 6 order: the text must parse *as the header* (syntax,
    field types, enum variants, required fields), then `kind` is compared
    with the preamble, then the value rules of section 6 are checked.  Type
    errors raise at once (herr); value-rule errors are recorded here (vfail,
    first wins) and raised by the caller after the kind comparison."""
    first = None


def vfail(msg):
    if _Deferred.first is None:
        _Deferred.first = msg


def as_struct(v, what, ext):
    if isinstance(v, RStruct):
        if v.dups:
            herr("%s: duplicate field `%s`" % (what, v.dups[0]))
        return v.fields
    if isinstance(v, RTuple) and not v.items:  # `()`: a struct with no fields
        return {}
    herr("%s: expected a struct" % what)


def as_option(v, what, ext):
    """Returns None for None, else the inner value."""
    if isinstance(v, RIdent) and v.name == "None":
        return None
    if isinstance(v, RTuple) and v.name == "Some":
        if len(v.items) != 1:
            herr("%s: Some(..) takes exactly one value" % what)
        return v.items[0]
    if "implicit_some" in ext:
        return v
    herr("%s: expected None or Some(..)" % what)


def as_int(v, what, lo, hi):
    if isinstance(v, RInt):
        if not lo <= v.v <= hi:
            herr("%s: %d out of range %d..=%d" % (what, v.v, lo, hi))
        return v.v
    herr("%s: expected an integer" % what)


def as_f32(v, what):
    if isinstance(v, RInt):
        x = float(v.v)
    elif isinstance(v, RFloat):
        x = v.v
    else:
        herr("%s: expected a number" % what)
    if math.isfinite(x):
        if abs(x) > F32_MAX * (1 + 2 ** -25):  # rounds to infinity in f32
            return float("inf")
        x = struct.unpack("<f", struct.pack("<f", max(-F32_MAX, min(F32_MAX, x))))[0]
    return x


def as_str(v, what):
    if isinstance(v, RStr):
        return v.s
    herr("%s: expected a string" % what)


def as_enum(v, what, variants):
    if isinstance(v, RIdent) and v.name in variants:
        return v.name
    if isinstance(v, RIdent):
        herr("%s: unknown variant `%s` (expected %s)" % (what, v.name, " | ".join(variants)))
    herr("%s: expected one of %s" % (what, " | ".join(variants)))


def as_tuple(v, what, n):
    if isinstance(v, RTuple) and v.name is None and len(v.items) == n:
        return v.items
    herr("%s: expected a %d-tuple" % (what, n))


U64_MAX = 2 ** 64 - 1
U32_MAX = 2 ** 32 - 1


def check_header(text):
    """Parse and check the section 6 header; returns a dict of facts."""
    _Deferred.first = None
    p = RonParser(text)
    try:
        root = p.parse_document()
    except RonError as e:
        herr("RON syntax error: %s" % e)
    ext = p.extensions
    f = as_struct(root, "header", ext)

    def req(fields, name, where):
        if name not in fields:
            herr("%s: missing field `%s`" % (where, name))
        return fields[name]

    h = {}
    h["kind"] = as_enum(req(f, "kind", "header"), "header.kind", ("Volume", "Cloud"))
    h["tool"] = as_str(req(f, "tool", "header"), "header.tool")
    src = as_option(f["source"], "header.source", ext) if "source" in f else None
    if src is not None:
        sf = as_struct(src, "header.source", ext)
        fn = as_str(req(sf, "file_name", "header.source"), "header.source.file_name")
        if "/" in fn or "\\" in fn:
            vfail("header.source.file_name must be a bare file name (no '/' or '\\')")
        sha = as_str(req(sf, "sha256", "header.source"), "header.source.sha256")
        if len(sha) != 64 or any(c not in "0123456789abcdef" for c in sha):
            vfail("header.source.sha256 must be 64 lowercase hex digits")
        as_int(req(sf, "bytes", "header.source"), "header.source.bytes", 0, U64_MAX)
        h["source"] = fn
    b = as_struct(req(f, "bounds", "header"), "header.bounds", ext)
    bmin = [as_f32(x, "header.bounds.min") for x in as_tuple(req(b, "min", "header.bounds"), "header.bounds.min", 3)]
    bmax = [as_f32(x, "header.bounds.max") for x in as_tuple(req(b, "max", "header.bounds"), "header.bounds.max", 3)]
    if not all(math.isfinite(x) for x in bmin + bmax):
        vfail("header.bounds must be finite")
    if any(lo > hi for lo, hi in zip(bmin, bmax)):
        vfail("header.bounds: min > max on some axis")
    h["bounds"] = [bmin, bmax]
    h["colour_space"] = as_enum(req(f, "colour_space", "header"), "header.colour_space",
                                ("SrgbPremultiplied", "LinearPremultiplied"))
    seed = as_option(f["seed"], "header.seed", ext) if "seed" in f else None
    if seed is not None:
        h["seed"] = as_int(seed, "header.seed", 0, U64_MAX)
    pm = req(f, "params", "header")
    if not isinstance(pm, RMap):
        herr("header.params: expected a map")
    params = {}
    for k, v in pm.pairs:
        ks = as_str(k, "header.params key")
        vs = as_str(v, "header.params[%s]" % json.dumps(ks))
        if ks in params:
            herr("header.params: duplicate key %s" % json.dumps(ks))
        params[ks] = vs
    h["params"] = params
    vol = as_option(f["volume"], "header.volume", ext) if "volume" in f else None
    if vol is not None:
        vf = as_struct(vol, "header.volume", ext)
        dims = [as_int(x, "header.volume.dims", 0, U32_MAX)
                for x in as_tuple(req(vf, "dims", "header.volume"), "header.volume.dims", 3)]
        for d in dims:
            if not 1 <= d <= 4096:
                vfail("header.volume.dims: %d not in 1..=4096" % d)
        mc = as_int(req(vf, "mip_count", "header.volume"), "header.volume.mip_count", 0, U32_MAX)
        fm = full_mip_count(dims)
        if not 1 <= mc <= fm:
            vfail("header.volume.mip_count %d not in 1..=%d (full_mip_count of %dx%dx%d)"
                 % (mc, fm, dims[0], dims[1], dims[2]))
        as_enum(req(vf, "texel", "header.volume"), "header.volume.texel", ("Rgba8Unorm",))
        nrm = as_option(vf["normals"], "header.volume.normals", ext) if "normals" in vf else None
        if nrm is not None:
            as_enum(nrm, "header.volume.normals", ("Rgba8Snorm",))
        # SPEC 6 / 8.4a (format 1.4): normal moments instead of mean normals, never both.
        mom = as_option(vf["moments"], "header.volume.moments", ext) if "moments" in vf else None
        if mom is not None:
            as_enum(mom, "header.volume.moments", ("Rgba8Snorm",))
        if nrm is not None and mom is not None:
            vfail("header.volume: normals and moments are both set (SPEC 6: one or the other)")
        h["volume"] = {"dims": dims, "mip_count": mc, "normals": nrm is not None,
                       "moments": mom is not None}
    else:
        h["volume"] = None
    if (h["kind"] == "Volume") != (h["volume"] is not None):
        vfail("header.volume must be present iff kind is Volume")
    h["value_error"] = _Deferred.first
    return h


# ------------------------------------------------------------- container

def read_container(data):
    """Sections 3, 4, 7 steps 1-5.  Returns (major, minor, kind, chunks)."""
    size = len(data)
    # step 1
    n = min(8, size)
    if data[:n] != MAGIC[:n]:
        fail("not a billow asset (bad magic)")
    # step 2
    if size < 12:
        fail("truncated: file is %d bytes, shorter than the 12-byte version field" % size)
    major, minor = struct.unpack_from("<HH", data, 8)
    if major != SUPPORTED_MAJOR:
        if major > SUPPORTED_MAJOR:
            fail("format version %d.%d is newer than this billow supports (%d.x); upgrade billow"
                 % (major, minor, SUPPORTED_MAJOR))
        fail("format version %d.%d is not supported (major %d does not exist; this reader supports %d.x)"
             % (major, minor, major, SUPPORTED_MAJOR))
    # step 3
    if size < 32:
        fail("truncated: file is %d bytes, shorter than the 32-byte preamble" % size)
    kind, file_len, reserved, crc = struct.unpack_from("<IQII", data, 12)
    calc = zlib.crc32(data[0:28]) & 0xFFFFFFFF
    if calc != crc:
        fail("preamble CRC mismatch: stored 0x%08X, computed 0x%08X" % (crc, calc))
    if kind not in KINDS:
        fail("unknown asset kind %d in preamble (expected 1 = Volume or 2 = Cloud)" % kind)
    if reserved != 0:
        fail("preamble reserved field is %d, must be 0" % reserved)
    # step 4
    if size < file_len:
        fail("truncated: file is %d bytes but the preamble says %d" % (size, file_len))
    if size > file_len:
        fail("trailing data: file is %d bytes but the preamble says %d" % (size, file_len))
    if size % 8:
        fail("file length %d is not a multiple of 8" % size)
    # step 5
    chunks = []
    off = 32
    while True:
        idx = len(chunks)
        if off >= size:
            fail("truncated: reached end of file at offset %d without an END chunk" % off)
        if size - off < 24:
            fail("truncated: chunk #%d at offset %d needs a 24-byte header but only %d bytes remain"
                 % (idx, off, size - off))
        tag = data[off:off + 4]
        elem, clen, cres, ccrc = struct.unpack_from("<IQII", data, off + 4)
        remain = size - (off + 24)
        if clen > remain:  # compared before any arithmetic on clen
            fail("chunk #%d '%s' at offset %d: length %d exceeds the %d bytes remaining in the file"
                 % (idx, tag_repr(tag), off, clen, remain))
        pad = (8 - clen % 8) % 8
        end = off + 24 + clen + pad
        if end > size:
            fail("chunk #%d '%s' at offset %d: payload plus %d padding bytes run past the end of the file"
                 % (idx, tag_repr(tag), off, pad))
        pstart = off + 24
        calc = zlib.crc32(data[pstart:pstart + clen], zlib.crc32(data[off:off + 20])) & 0xFFFFFFFF
        if calc != ccrc:
            fail("chunk #%d '%s' at offset %d: CRC mismatch: stored 0x%08X, computed 0x%08X"
                 % (idx, tag_repr(tag), off, ccrc, calc))
        if not all(0x20 <= c <= 0x7E for c in tag) or tag[0] == 0x20:
            fail("chunk #%d at offset %d: tag '%s' is not four printable ASCII bytes starting with a non-space"
                 % (idx, off, tag_repr(tag)))
        if elem not in ELEM_TYPES:
            fail("chunk #%d '%s' at offset %d: unknown element type %d" % (idx, tag_repr(tag), off, elem))
        if cres != 0:
            fail("chunk #%d '%s' at offset %d: reserved field is %d, must be 0" % (idx, tag_repr(tag), off, cres))
        ename, esize = ELEM_TYPES[elem]
        if clen % esize:
            fail("chunk #%d '%s' at offset %d: length %d is not a multiple of the %s element size %d"
                 % (idx, tag_repr(tag), off, clen, ename, esize))
        if any(data[pstart + clen:end]):
            fail("chunk #%d '%s' at offset %d: padding bytes are not zero" % (idx, tag_repr(tag), off))
        # step 5.5
        if idx == 0 and tag != b"HEAD":
            fail("first chunk (offset 32) is '%s', expected HEAD" % tag_repr(tag))
        if idx > 0 and tag == b"HEAD":
            fail("chunk #%d at offset %d: HEAD may appear only as the first chunk" % (idx, off))
        if tag in (b"HEAD", b"END ") and elem != E_OPAQUE:
            fail("chunk '%s' at offset %d has element type %d, must be 0 (Opaque)" % (tag_repr(tag), off, elem))
        chunks.append({"tag": tag, "elem": elem, "len": clen, "off": off,
                       "payload": data[pstart:pstart + clen]})
        if tag == b"END ":
            if clen != 0:
                fail("END chunk at offset %d has length %d, must be 0" % (off, clen))
            if end != size:
                fail("data after the END chunk: END ends at %d but the file is %d bytes" % (end, size))
            break
        off = end
    return major, minor, KINDS[kind], chunks


# ------------------------------------------------------------ Volume (8)

def volume_level_check(ch, dims, level, what):
    w, h, d = mip_dims(dims, level)
    need = w * h * d * 4
    if ch["len"] != need:
        fail("%s level %d: length %d, expected %d (%dx%dx%d texels x 4 bytes)"
             % (what, level, ch["len"], need, w, h, d))
    return [w, h, d]


def band_level_check(ch, dims, level, compressed, what):
    if not compressed:
        return volume_level_check(ch, dims, level, what)
    w, h, d = mip_dims(dims, level)
    bc7_check(ch, w, h, d, "%s level %d" % (what, level))
    return [w, h, d]


def check_cells(ch, what):
    if ch["len"] % 144:
        fail("%s: length %d is not a multiple of 144 (one prism = 36 f32)" % (what, ch["len"]))
    k = first_nonfinite(ch["payload"])
    if k >= 0:
        fail("%s: float #%d (prism %d) is not finite" % (what, k, k // 36))
    return ch["len"] // 144


def need_elem(ch, elem, what):
    if ch["elem"] != elem:
        fail("%s chunk at offset %d has element type %d (%s), expected %d (%s)"
             % (what, ch["off"], ch["elem"], ELEM_TYPES[ch["elem"]][0], elem, ELEM_TYPES[elem][0]))


def bc7_check(ch, w, h, d, what):
    # SPEC 12.1: n = ceil(w/4) * ceil(h/4) * d blocks; a block mask of m bytes (one bit per
    # block, LSB first, padded with zero bits to a multiple of 16 bytes), then 16 bytes per
    # stored block.
    n = ((w + 3) // 4) * ((h + 3) // 4) * d
    m = -(-(-(-n // 8)) // 16) * 16
    p = ch["payload"]
    if len(p) < m:
        fail("%s: length %d, shorter than its %d-byte block mask (%d blocks)" % (what, len(p), m, n))
    mask = int.from_bytes(p[:m], "little")
    if mask >> n:
        fail("%s: block mask has bits set beyond its %d blocks" % (what, n))
    s = bin(mask).count("1")
    if len(p) != m + 16 * s:
        fail("%s: length %d, expected %d (a %d-byte mask and %d stored blocks)" % (what, len(p), m + 16 * s, m, s))


def raw_or_blocks(by_tag, raw, comp):
    # SPEC 12.1: a compressed chunk replaces its raw chunk one for one; a file has one
    # kind or the other for a given texture stream, never both.
    r, c = by_tag.get(raw, []), by_tag.get(comp, [])
    if r and c:
        fail("both %s and %s chunks: a level is raw or compressed, not both"
             % (tag_str(raw), tag_str(comp)))
    return (c, True) if c else (r, False)


def level_len_check(ch, w, h, d, compressed, what):
    if compressed:
        bc7_check(ch, w, h, d, what)
        return
    need = w * h * d * 4
    if ch["len"] != need:
        fail("%s: length %d, expected %d (%dx%dx%d texels x 4 bytes)" % (what, ch["len"], need, w, h, d))


def decode_volume(header, by_tag, out):
    vol = header["volume"]
    dims, mc, has_mean, has_mom = vol["dims"], vol["mip_count"], vol["normals"], vol["moments"]
    has_n = has_mean or has_mom
    # SPEC 8.1 / 8.4a (format 1.4): a volume with `moments` stores VMOM/BMOM/VMB7/BMB7
    # where one with `normals` stores VNRM/BNRM/VNB7/BNB7, under the same rules; a
    # chunk of the family the header does not declare is an error, not skipped.
    mean_tags = (b"VNRM", b"VNB7", b"BNRM", b"BNB7")
    mom_tags = (b"VMOM", b"VMB7", b"BMOM", b"BMB7")
    if has_mom:
        own, other, field = mom_tags, mean_tags, "moments"
    else:
        own, other, field = mean_tags, mom_tags, "normals"
    for t in other + (() if has_n else own):
        if by_tag.get(t):
            fail("Volume: %s chunk but the header %s (SPEC 8.1)"
                 % (tag_str(t), "sets volume.%s" % field if has_n else "has neither normals nor moments"))
    t_raw, t_bc, t_braw, t_bbc = own
    vlev, vbc = raw_or_blocks(by_tag, b"VLEV", b"VLB7")
    vnrm, nbc = raw_or_blocks(by_tag, t_raw, t_bc)
    if vnrm and has_n and vbc != nbc:
        fail("Volume: colour and normals must both be raw or both compressed (SPEC 8.1)")
    out["compressed"] = vbc
    cell = by_tag.get(b"CELL", [])
    vbnd = by_tag.get(b"VBND", [])
    # SPEC 12.1 (format 1.3): BLB7/BNB7 replace BLEV/BNRM one for one.
    blev, blbc = raw_or_blocks(by_tag, b"BLEV", b"BLB7")
    bnrm, bnbc = raw_or_blocks(by_tag, t_braw, t_bbc)
    if bnrm and blbc != bnbc:
        fail("Volume: band colour and normals must both be raw or both compressed (SPEC 12.1)")
    if blbc and not vbc:
        fail("Volume: BLB7 chunks but a raw base texture (SPEC 12.1: BLB7 needs VLB7)")
    out["compressed_bands"] = blbc
    bcel = by_tag.get(b"BCEL", [])
    for tag, lst, elem in ((b"VLEV", vlev, E_U8), (t_bc if nbc else t_raw, vnrm, E_U8 if nbc else E_I8),
                           (b"CELL", cell, E_F32),
                           (b"VBND", vbnd, E_U32), (b"BLEV", blev, E_U8),
                           (t_bbc if bnbc else t_braw, bnrm, E_U8 if bnbc else E_I8),
                           (b"BCEL", bcel, E_F32)):
        for ch in lst:
            need_elem(ch, elem, tag_str(tag))
    ctag = "VLB7" if vbc else "VLEV"
    ntag = tag_str(t_bc if nbc else t_raw)
    bntag = tag_str(t_bbc if bnbc else t_braw)
    if len(vlev) != mc:
        fail("Volume: %d %s chunks, header mip_count is %d" % (len(vlev), ctag, mc))
    level_sizes = []
    for i, ch in enumerate(vlev):
        w, h, d = mip_dims(dims, i)
        level_len_check(ch, w, h, d, vbc, "%s level %d" % (ctag, i))
        level_sizes.append([w, h, d])
    want_n = mc if has_n else 0
    if len(vnrm) != want_n:
        fail("Volume: %d %s chunks, expected %d (%s)"
             % (len(vnrm), ntag, want_n, "%s set" % field if has_n else "header has no normals"))
    for i, ch in enumerate(vnrm):
        w, h, d = mip_dims(dims, i)
        level_len_check(ch, w, h, d, nbc, "%s level %d" % (ntag, i))
    if len(cell) != 1:
        fail("Volume: %d CELL chunks, expected exactly 1" % len(cell))
    cells = check_cells(cell[0], "CELL")

    bands = []
    if not vbnd:
        if blev or bnrm or bcel:
            fail("Volume: BLEV/%s/BLB7/%s/BCEL chunk without a VBND chunk"
                 % (tag_str(t_braw), tag_str(t_bbc)))
    else:
        if len(vbnd) > 1:
            fail("Volume: %d VBND chunks, at most 1 allowed" % len(vbnd))
        vb = vbnd[0]
        if vb["len"] == 0 or vb["len"] % 32:
            fail("VBND: length %d is not a positive multiple of 32" % vb["len"])
        words = le_u32s(vb["payload"])
        prev_f, prev_m = 0, mc
        for i in range(len(words) // 8):
            f, dx, dy, dz, m, r0, r1, r2 = words[8 * i:8 * i + 8]
            bi = i + 1
            if r0 or r1 or r2:
                fail("VBND band %d: reserved words must be 0" % bi)
            if not prev_f < f <= 16:
                fail("VBND band %d: first_level %d must satisfy %d < first_level <= 16" % (bi, f, prev_f))
            if prev_m < f - prev_f + 1:
                fail("VBND band %d: previous band has %d levels but needs >= %d (first_level %d - %d + 1)"
                     % (bi, prev_m, f - prev_f + 1, f, prev_f))
            bd = [dx, dy, dz]
            for d in bd:
                if not 1 <= d <= 4096:
                    fail("VBND band %d: dims %dx%dx%d not each in 1..=4096" % (bi, dx, dy, dz))
            fm = full_mip_count(bd)
            if not 1 <= m <= fm:
                fail("VBND band %d: mip_count %d not in 1..=%d" % (bi, m, fm))
            bands.append({"first_level": f, "dims": bd, "mip_levels": m})
            prev_f, prev_m = f, m
        total = sum(b["mip_levels"] for b in bands)
        if len(blev) != total:
            fail("Volume: %d %s chunks, expected %d (sum of band mip_counts)"
                 % (len(blev), "BLB7" if blbc else "BLEV", total))
        want = total if has_n else 0
        if len(bnrm) != want:
            fail("Volume: %d %s chunks, expected %d" % (len(bnrm), bntag, want))
        if len(bcel) != len(bands):
            fail("Volume: %d BCEL chunks, expected %d (one per band)" % (len(bcel), len(bands)))
        k = 0
        for bi, b in enumerate(bands, 1):
            b["level_sizes"] = [band_level_check(blev[k + j], b["dims"], j, blbc,
                                                 "band %d %s" % (bi, "BLB7" if blbc else "BLEV"))
                                for j in range(b["mip_levels"])]
            if has_n:
                for j in range(b["mip_levels"]):
                    band_level_check(bnrm[k + j], b["dims"], j, bnbc,
                                     "band %d %s" % (bi, bntag))
            k += b["mip_levels"]
            b["cells"] = check_cells(bcel[bi - 1], "band %d BCEL" % bi)
    out.update({
        "dims": dims,
        "mip_levels": mc,
        "level_sizes": level_sizes,
        "level_bytes": [w * h * d * 4 for w, h, d in level_sizes],
        "normals": has_mean,
        "moments": has_mom,
        "colour_space": header["colour_space"],
        "cells": cells,
        "bands": len(bands),
    })
    if bands:
        out["band_info"] = bands
        last = bands[-1]
        out["max_lod"] = last["first_level"] + last["mip_levels"] - 1
    else:
        out["max_lod"] = mc - 1


# ------------------------------------------------------------- Cloud (9)

CLOUD_TABLE = [  # tag, elem, record bytes (None = per-chunk length rule), repeatable
    (b"CLVL", E_U32, 16, False),
    (b"CLVF", E_F32, 8, False),
    (b"BBRD", E_F32, 144, False),
    (b"BBIX", E_U32, 16, False),
    (b"ATLS", E_U32, 16, False),
    (b"ATEX", E_U8, None, True),
    (b"ANRM", E_U8, None, True),
    (b"ATB7", E_U8, None, True),
    (b"ANB7", E_U8, None, True),
    (b"MMAT", E_F32, 32, False),
    (b"MMAI", E_U32, 16, False),
    (b"MTXI", E_U32, 16, False),
    (b"MTEX", E_U8, None, True),
    (b"MTB7", E_U8, None, True),
    (b"TVTX", E_F32, 32, False),
    (b"TIDX", E_U32, 16, False),
    (b"FVTX", E_F32, 44, False),
    (b"FIDX", E_U32, 20, False),
]


def decode_cloud(header, by_tag, out):
    one = {}
    for tag, elem, rec, rep in CLOUD_TABLE:
        lst = by_tag.get(tag, [])
        for ch in lst:
            need_elem(ch, elem, tag_str(tag))
            if rec and ch["len"] % rec:
                fail("%s: length %d is not a multiple of the %d-byte record" % (tag_str(tag), ch["len"], rec))
        if not rep:
            if len(lst) != 1:
                fail("Cloud: %d %s chunks, expected exactly 1" % (len(lst), tag_str(tag)))
            one[tag] = lst[0]["payload"]

    # 9.2 levels
    clvl = le_u32s(one[b"CLVL"])
    nlev = len(clvl) // 4
    if nlev < 1:
        fail("CLVL: a cloud needs at least one level")
    nbb = len(one[b"BBRD"]) // 144
    if len(one[b"BBIX"]) // 16 != nbb:
        fail("BBIX has %d records but BBRD has %d billboards" % (len(one[b"BBIX"]) // 16, nbb))
    natl = len(one[b"ATLS"]) // 16
    levels = []
    nb = na = 0
    for i in range(nlev):
        fb, cb, fa, ca = clvl[4 * i:4 * i + 4]
        if fb != nb or fa != na:
            fail("CLVL level %d starts at billboard %d / atlas %d, expected %d / %d (consecutive ranges)"
                 % (i, fb, fa, nb, na))
        if cb < 1 or ca < 1:
            fail("CLVL level %d has %d billboards and %d atlases; each level needs at least one of each"
                 % (i, cb, ca))
        nb, na = fb + cb, fa + ca
        levels.append((fb, cb, fa, ca))
    if nb != nbb:
        fail("CLVL levels cover %d billboards but BBRD has %d" % (nb, nbb))
    if na != natl:
        fail("CLVL levels cover %d atlases but ATLS has %d" % (na, natl))
    clvf = le_f32s(one[b"CLVF"])
    if len(clvf) // 2 != nlev:
        fail("CLVF has %d records but CLVL has %d levels" % (len(clvf) // 2, nlev))
    for i in range(nlev):
        eps, td = clvf[2 * i], clvf[2 * i + 1]
        if not (math.isfinite(eps) and eps > 0 and math.isfinite(td) and td > 0):
            fail("CLVF level %d: epsilon and texel_density must be finite and > 0" % i)

    # 9.3 billboards
    if first_nonfinite(one[b"BBRD"]) >= 0:
        k = first_nonfinite(one[b"BBRD"])
        fail("BBRD billboard %d: float #%d is not finite" % (k // 36, k % 36))
    bbrd = le_f32s(one[b"BBRD"])
    bbix = le_u32s(one[b"BBIX"])
    level_of_bb = []
    level_of_atlas = []
    for li, (fb, cb, fa, ca) in enumerate(levels):
        level_of_bb += [li] * cb
        level_of_atlas += [li] * ca
    for b in range(nbb):
        r = bbrd[36 * b:36 * b + 36]
        n = r[0:3]
        ln = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        if abs(ln - 1) > 1e-3:
            fail("BBRD billboard %d: plane normal length %.6g, must be 1 within 1e-3" % (b, ln))
        for side, uv in (("front_uv", r[28:32]), ("back_uv", r[32:36])):
            u0, v0, u1, v1 = uv
            if not (0 <= u0 <= u1 <= 1 and 0 <= v0 <= v1 <= 1):
                fail("BBRD billboard %d: %s (%g, %g, %g, %g) violates 0 <= u0 <= u1 <= 1, 0 <= v0 <= v1 <= 1"
                     % (b, side, u0, v0, u1, v1))
        fa_, ba_, parent, _elements = bbix[4 * b:4 * b + 4]
        li = level_of_bb[b]
        for side, a in (("front_atlas", fa_), ("back_atlas", ba_)):
            if a >= natl or level_of_atlas[a] != li:
                fail("BBIX billboard %d: %s %d is not an atlas of its level %d" % (b, side, a, li))
        if li == nlev - 1:
            if parent != NONE_U32:
                fail("BBIX billboard %d (last level): parent must be 0xFFFFFFFF, is %d" % (b, parent))
            # Section 9.3 says parent_corners are "the corners themselves in the
            # last level", but both frozen cloud fixtures violate that (and the
            # projection rule), so no geometric check is made: SPEC_GAPS.md.
        else:
            nfb, ncb = levels[li + 1][0], levels[li + 1][1]
            if not nfb <= parent < nfb + ncb:
                fail("BBIX billboard %d: parent %s is not a billboard of the next level (%d..%d)"
                     % (b, "0xFFFFFFFF" if parent == NONE_U32 else parent, nfb, nfb + ncb))

    # 9.4 atlases
    atls = le_u32s(one[b"ATLS"])
    atlases = []
    for a in range(natl):
        w, h, m, res = atls[4 * a:4 * a + 4]
        if not (1 <= w <= 16384 and 1 <= h <= 16384):
            fail("ATLS atlas %d: size %dx%d, sides must be in 1..=16384" % (a, w, h))
        fm = max(w, h).bit_length()
        if not 1 <= m <= fm:
            fail("ATLS atlas %d: mip_count %d not in 1..=%d" % (a, m, fm))
        if res:
            fail("ATLS atlas %d: reserved word must be 0" % a)
        atlases.append((w, h, m))
    atex, abc = raw_or_blocks(by_tag, b"ATEX", b"ATB7")
    anrm, nbc = raw_or_blocks(by_tag, b"ANRM", b"ANB7")
    mtex_c = by_tag.get(b"MTB7", [])
    comp = abc or nbc or bool(mtex_c)
    if comp and (by_tag.get(b"ATEX") or by_tag.get(b"ANRM") or by_tag.get(b"MTEX")):
        fail("Cloud: both raw (ATEX/ANRM/MTEX) and compressed (ATB7/ANB7/MTB7) texture chunks")
    out["compressed"] = comp
    at, nt = ("ATB7", "ANB7") if comp else ("ATEX", "ANRM")
    expected = [(a, i, max(1, w >> i), max(1, h >> i)) for a, (w, h, m) in enumerate(atlases) for i in range(m)]
    if len(atex) != len(expected):
        fail("Cloud: %d %s chunks, expected %d (sum of atlas mip_counts)" % (len(atex), at, len(expected)))
    for ch, (a, i, w, h) in zip(atex, expected):
        level_len_check(ch, w, h, 1, comp, "%s atlas %d level %d" % (at, a, i))
    if anrm:
        if len(anrm) != len(atex):
            fail("Cloud: %d %s chunks, expected none or %d (one per %s)" % (len(anrm), nt, len(atex), at))
        for ch, ach, (a, i, w, h) in zip(anrm, atex, expected):
            if comp:
                level_len_check(ch, w, h, 1, True, "%s atlas %d level %d" % (nt, a, i))
            elif ch["len"] != ach["len"]:
                fail("%s atlas %d level %d: length %d differs from its %s length %d"
                     % (nt, a, i, ch["len"], at, ach["len"]))

    # 9.5 materials, textures, meshes
    nmat = len(one[b"MMAT"]) // 32
    if len(one[b"MMAI"]) // 16 != nmat:
        fail("MMAI has %d records but MMAT has %d materials" % (len(one[b"MMAI"]) // 16, nmat))
    mtxi = le_u32s(one[b"MTXI"])
    ntex = len(mtxi) // 4
    mtex = mtex_c if comp else by_tag.get(b"MTEX", [])
    mt = "MTB7" if comp else "MTEX"
    if len(mtex) != ntex:
        fail("Cloud: %d %s chunks, MTXI has %d textures" % (len(mtex), mt, ntex))
    for t in range(ntex):
        w, h, wu, wv = mtxi[4 * t:4 * t + 4]
        if not (1 <= w <= 16384 and 1 <= h <= 16384):
            fail("MTXI texture %d: size %dx%d, sides must be in 1..=16384" % (t, w, h))
        if wu > 2 or wv > 2:
            fail("MTXI texture %d: wrap codes (%d, %d) must be 0..=2" % (t, wu, wv))
        level_len_check(mtex[t], w, h, 1, comp, "%s texture %d" % (mt, t))
    k = first_nonfinite(one[b"MMAT"])
    if k >= 0:
        fail("MMAT material %d: float #%d is not finite" % (k // 8, k % 8))
    mmat = le_f32s(one[b"MMAT"])
    mmai = le_u32s(one[b"MMAI"])
    for m in range(nmat):
        if any(x != 0 for x in mmat[8 * m + 5:8 * m + 8]):
            fail("MMAT material %d: reserved floats must be 0" % m)
        tex, mode, ds, res = mmai[4 * m:4 * m + 4]
        if tex != NONE_U32 and tex >= ntex:
            fail("MMAI material %d: texture index %d out of range (%d textures)" % (m, tex, ntex))
        if mode > 2:
            fail("MMAI material %d: alpha_mode %d must be 0..=2" % (m, mode))
        if ds > 1:
            fail("MMAI material %d: double_sided %d must be 0 or 1" % (m, ds))
        if res:
            fail("MMAI material %d: reserved word must be 0" % m)

    def mesh(vtag, itag, vrec, irec):
        if first_nonfinite(one[vtag]) >= 0:
            fail("%s: vertex %d has a non-finite float" % (tag_str(vtag), first_nonfinite(one[vtag]) // (vrec // 4)))
        nv = len(one[vtag]) // vrec
        idx = le_u32s(one[itag])
        step = irec // 4
        nt = len(idx) // step
        for t in range(nt):
            tri = idx[step * t:step * t + step]
            for c in range(3):
                if tri[c] >= nv:
                    fail("%s triangle %d: vertex index %d out of range (%d vertices)" % (tag_str(itag), t, tri[c], nv))
            if tri[3] >= nmat:
                fail("%s triangle %d: material %d out of range (%d materials)" % (tag_str(itag), t, tri[3], nmat))
        return nv, nt, idx

    kv, kt, _ = mesh(b"TVTX", b"TIDX", 32, 16)
    fv, ft, fidx = mesh(b"FVTX", b"FIDX", 44, 20)
    lvl0_bb = levels[0][1]
    owner = {}
    for t in range(ft):
        bb = fidx[5 * t + 4]
        if bb >= lvl0_bb:
            fail("FIDX triangle %d: billboard %d is not a level-0 billboard (level 0 has %d)" % (t, bb, lvl0_bb))
        for c in range(3):
            v = fidx[5 * t + c]
            if owner.setdefault(v, bb) != bb:
                fail("FIDX: vertex %d is shared by triangles of billboards %d and %d" % (v, owner[v], bb))

    known = {t for t, _, _, _ in CLOUD_TABLE}
    out.update({
        "levels": nlev,
        "billboards": nbb,
        "atlases": natl,
        "meshes": (1 if kt else 0) + (1 if ft else 0),
        "level_ranges": [list(l) for l in levels],
        "atlas_sizes": [[w, h, m] for w, h, m in atlases],
        "atlas_levels": len(atex),
        "normal_maps": bool(anrm),
        "materials": nmat,
        "textures": ntex,
        "kept_mesh": {"vertices": kv, "triangles": kt},
        "foliage_mesh": {"vertices": fv, "triangles": ft},
        "colour_space": header["colour_space"],
    })
    return known


# ------------------------------------------------------------------ main

VOLUME_TAGS = {b"VLEV", b"VNRM", b"CELL", b"VBND", b"BLEV", b"BNRM", b"BCEL", b"VLB7", b"VNB7", b"BLB7", b"BNB7",
               b"VMOM", b"BMOM", b"VMB7", b"BMB7"}


def read_billow(data):
    major, minor, kind, chunks = read_container(data)
    # step 6
    head = chunks[0]["payload"]
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as e:
        fail("HEAD payload is not valid UTF-8 (byte %d)" % e.start)
    try:
        header = check_header(text)
    except HeaderError as e:
        fail("HEAD: %s" % e)
    if header["kind"] != kind:
        fail("HEAD kind %s does not match the preamble kind %s" % (header["kind"], kind))
    if header["value_error"]:
        fail("HEAD: %s" % header["value_error"])
    # step 7
    by_tag = {}
    for ch in chunks[1:-1]:
        by_tag.setdefault(ch["tag"], []).append(ch)
    out = {"ok": True, "major": major, "minor": minor, "kind": kind,
           "chunks": [tag_str(c["tag"]) for c in chunks]}
    if kind == "Volume":
        decode_volume(header, by_tag, out)
        known = VOLUME_TAGS
    else:
        known = decode_cloud(header, by_tag, out)
    skipped = sorted({tag_str(t) for t in by_tag if t not in known})
    if skipped:
        out["skipped_unknown"] = skipped
    return out


def process(path):
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as e:
        return {"path": path, "ok": False, "error": "cannot read file: %s" % (e.strerror or e)}
    try:
        res = read_billow(data)
    except BillowError as e:
        return {"path": path, "ok": False, "error": str(e)}
    except Exception as e:  # last resort: never a traceback
        return {"path": path, "ok": False, "error": "internal reader error: %s: %s" % (type(e).__name__, e)}
    return dict([("path", path)] + list(res.items()))


def main(argv):
    if len(argv) < 2:
        sys.stderr.write("usage: %s FILE.billow [FILE.billow ...]\n" % argv[0])
        return 2
    bad = False
    for p in argv[1:]:
        r = process(p)
        bad |= not r["ok"]
        sys.stdout.write(json.dumps(r) + "\n")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
