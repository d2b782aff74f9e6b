#!/usr/bin/env python3
"""Writes the initial fuzz corpora (fuzz/corpus/<target>/) from the project's fixtures and
small hand-written inputs. Run from the repository root: python3 fuzz/seeds/make_seeds.py.
The committed corpora are these seeds plus what `cargo fuzz` found, minimised with
`cargo fuzz cmin`."""
import base64, glob, hashlib, json, os, re, shutil, struct

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")

def put(target, data):
    if isinstance(data, str):
        data = data.encode()
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    name = "seed-" + hashlib.sha1(data).hexdigest()[:16]
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)

# asset_reader: the format fixtures.
for p in sorted(glob.glob(os.path.join(ROOT, "fixtures", "format", "*.billow"))):
    put("asset_reader", open(p, "rb").read())

# gltf_import: a triangle (positions, normals, uvs, indices) as .gltf with a data: URI,
# with a buf.bin URI, with a texture, and as .glb.
def tri_buffers():
    pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    nrm = struct.pack("<9f", 0, 0, 1, 0, 0, 1, 0, 0, 1)
    uv = struct.pack("<6f", 0, 0, 1, 0, 0, 1)
    idx = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    return pos + nrm + uv + idx

def tri_doc(uri, blen, texture=False, extra=None):
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "children": [1]}, {"mesh": 0, "translation": [1, 0, 0], "scale": [2, 2, 2]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0.25, 1]}, "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True}],
        "buffers": [{"byteLength": blen}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 36},
            {"buffer": 0, "byteOffset": 72, "byteLength": 24},
            {"buffer": 0, "byteOffset": 96, "byteLength": 6, "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
    }
    if uri is not None:
        doc["buffers"][0]["uri"] = uri
    if texture:
        doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        doc["textures"] = [{"source": 0, "sampler": 0}]
        doc["samplers"] = [{"wrapS": 33648}]
        doc["images"] = [{"uri": "tex.png"}]
    if extra:
        doc.update(extra)
    return doc

buf = tri_buffers()
data_uri = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
put("gltf_import", json.dumps(tri_doc(data_uri, len(buf))))
put("gltf_import", json.dumps(tri_doc(data_uri, len(buf), texture=True)))
put("gltf_import", json.dumps(tri_doc("buf.bin", 102)))
sparse = tri_doc(data_uri, len(buf))
sparse["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 3, "componentType": 5123}, "values": {"bufferView": 1}}
put("gltf_import", json.dumps(sparse))

def glb(doc, binary):
    j = json.dumps(doc, separators=(",", ":")).encode()
    j += b" " * (-len(j) % 4)
    binary += b"\0" * (-len(binary) % 4)
    out = struct.pack("<II", len(j), 0x4E4F534A) + j + struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<III", 0x46546C67, 2, 12 + len(out)) + out
put("gltf_import", glb(tri_doc(None, len(buf)), buf))
put("gltf_import", glb(tri_doc(None, len(buf), texture=True), buf))
oak = open(os.path.join(ROOT, "fixtures", "oak", "eztree_oak_medium.gltf")).read()
put("gltf_import", oak.replace("eztree_oak_medium.bin", "buf.bin"))

# obj_import: OBJ, NUL, MTL.
mtl = open(os.path.join(ROOT, "fixtures", "oak", "eztree_oak_medium.mtl")).read()
mtl = mtl.replace("oak_color_1k.jpg", "tex.png").replace("oak_color.png", "tex.png")
wall = open(os.path.join(ROOT, "fixtures", "scenes", "wall.obj")).read()
put("obj_import", wall)
put("obj_import", "mtllib in.mtl\n" + wall.replace("vn 1 0 0\n", "vn 1 0 0\nusemtl leaves\n") + "\0" + mtl)
put("obj_import", """mtllib in.mtl
o quad
v 0 0 0 1 0 0
v 1 0 0 0 1 0
v 1 1 0 0 0 1
v 0 1 0 1 1 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
g leaves
usemtl bark
s 1
f 1/1/1 2/2/1 3/3/1 4/4/1
f -4/-4 -3/-3 -2/-2
l 1 2
p 3
\0newmtl bark
Kd 0.5 0.4 0.3
Tr 0.25
map_Kd -s 1 1 1 -bm 0.5 tex.png
map_d tex.png
""")
head = "".join(open(os.path.join(ROOT, "fixtures", "oak", "eztree_oak_medium.obj")).readlines()[:60])
put("obj_import", head + "\0" + mtl)

# combine_expr: the documented presets and expressions.
for e in ["mean", "max", "min", "opaque",
          "expr:max(px, nx) * 0.5 + mean(py, ny, pz, nz) * 0.5",
          "expr:mix(max(px,nx,py,ny,pz,nz), mean(px,nx,py,ny,pz,nz), 0.25)",
          "expr:rgba(px.r, py.g, pz.b, max(px.a, nx.a))",
          "expr:clamp(sum(px, nx) / 2 - -1.5e-1, 0, 1)",
          "expr:abs(px - nx) * (1 / 3)",
          "max(px, nx) * 0.5 + mean(py, ny, pz, nz) * 0.5"]:
    put("combine_expr", e)

# scene_ron: the scene fixtures (not the 100 KB gallery).
for p in sorted(glob.glob(os.path.join(ROOT, "fixtures", "scenes", "*.ron"))):
    put("scene_ron", open(p, "rb").read())
