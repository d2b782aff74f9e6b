// Reads .ktx2 files with ktx-parse (the KTX2 reader of three.js's KTX2Loader and
// glTF-Transform) and checks what billow promises of its 3D-texture exports: one face, no
// array layers, no supercompression, RGBA8 (sRGB or linear, matching the DFD's transfer
// function), the premultiplied flag in the DFD, and a full MIP chain whose level sizes match
// the halved dimensions; or the same as BC7 blocks (BC7_SRGB_BLOCK / BC7_UNORM_BLOCK, DFD colour
// model BC7, each level 16 bytes per 4x4 block of each z slice: billow voxelize --compress bc,
// the default). A Zstandard-supercompressed file (`--ktx2-zstd LEVEL`, supercompressionScheme
// 2) is given as ZSTD_FILE=PLAIN_FILE: besides the checks above, each of its levels is inflated
// with zstddec (the decoder three.js's KTX2Loader uses) and must equal PLAIN_FILE's level byte
// for byte, its uncompressedByteLength that level's length, and the two files' headers but the
// scheme and their DFDs must agree. Used by `make check-ktx2`; exits 1 on a mismatch, 2 when
// it cannot run.
// Usage: node check.mjs MODULE_DIR FILE|ZSTD_FILE=PLAIN_FILE...
import fs from 'fs';
import path from 'path';
import { pathToFileURL } from 'url';

const [moduleDir, ...args] = process.argv.slice(2);
let ktx;
try {
  ktx = await import(pathToFileURL(path.join(moduleDir, 'ktx-parse', 'dist', 'index.mjs')).href);
} catch (e) {
  console.error(`check.mjs: ktx-parse not found under ${moduleDir} (make check-ktx2 installs it)`);
  process.exit(2);
}
const pairs = args.map((a) => a.split('='));
let zstd = null;
if (pairs.some((p) => p.length > 1)) {
  try {
    const z = await import(pathToFileURL(path.join(moduleDir, 'zstddec', 'dist', 'zstddec.modern.js')).href);
    zstd = new z.ZSTDDecoder();
    await zstd.init();
  } catch (e) {
    console.error(`check.mjs: zstddec not found under ${moduleDir} (make check-ktx2 installs it)`);
    process.exit(2);
  }
}
const KTX2_SS_NONE = 0, KTX2_SS_ZSTD = 2;
const files = pairs.map((p) => p[0]);
const plainOf = new Map(pairs.filter((p) => p.length > 1).map((p) => [p[0], p[1]]));
const VK_R8G8B8A8_UNORM = 37, VK_R8G8B8A8_SRGB = 43;
const VK_BC7_UNORM = 145, VK_BC7_SRGB = 146, KHR_DF_MODEL_BC7 = 134;
let bad = 0;
for (const f of files) {
  const problems = [];
  let c;
  try {
    c = ktx.read(new Uint8Array(fs.readFileSync(f)));
  } catch (e) {
    console.log(`${f}: not readable: ${e.message || e}`);
    bad++;
    continue;
  }
  const d = c.dataFormatDescriptor[0];
  const premul = (d.flags & ktx.KHR_DF_FLAG_ALPHA_PREMULTIPLIED) !== 0;
  const srgb = d.transferFunction === ktx.KHR_DF_TRANSFER_SRGB;
  const bc7 = d.colorModel === KHR_DF_MODEL_BC7;
  const want = bc7 ? (srgb ? VK_BC7_SRGB : VK_BC7_UNORM) : (srgb ? VK_R8G8B8A8_SRGB : VK_R8G8B8A8_UNORM);
  if (c.vkFormat !== want) problems.push(`vkFormat ${c.vkFormat} does not match the DFD (model ${d.colorModel}, transfer ${d.transferFunction})`);
  if (!premul) problems.push('DFD lacks KHR_DF_FLAG_ALPHA_PREMULTIPLIED');
  if (c.faceCount !== 1 || c.layerCount !== 0) problems.push(`faces ${c.faceCount}, layers ${c.layerCount}`);
  const plainFile = plainOf.get(f);
  const wantScheme = plainFile ? KTX2_SS_ZSTD : KTX2_SS_NONE;
  if (c.supercompressionScheme !== wantScheme) problems.push(`supercompression ${c.supercompressionScheme}, expected ${wantScheme}`);
  if (!(c.pixelDepth > 0)) problems.push('not a 3D texture');
  const dims = [c.pixelWidth, c.pixelHeight, c.pixelDepth];
  const full = 1 + Math.floor(Math.log2(Math.max(...dims)));
  if (c.levels.length !== full) problems.push(`${c.levels.length} levels, a full chain has ${full}`);
  let plain = null;
  if (plainFile) {
    try {
      plain = ktx.read(new Uint8Array(fs.readFileSync(plainFile)));
    } catch (e) {
      problems.push(`${plainFile}: not readable: ${e.message || e}`);
    }
  }
  if (plain) {
    for (const k of ['vkFormat', 'typeSize', 'pixelWidth', 'pixelHeight', 'pixelDepth', 'layerCount', 'faceCount']) {
      if (c[k] !== plain[k]) problems.push(`${k} ${c[k]}, ${plainFile} has ${plain[k]}`);
    }
    if (JSON.stringify(c.dataFormatDescriptor) !== JSON.stringify(plain.dataFormatDescriptor)) problems.push(`DFD differs from ${plainFile}'s`);
    if (c.levels.length !== plain.levels.length) problems.push(`${c.levels.length} levels, ${plainFile} has ${plain.levels.length}`);
  }
  let stored = 0, inflatedTotal = 0;
  c.levels.forEach((l, i) => {
    const [w, h, z] = dims.map((x) => Math.max(1, x >> i));
    const n = bc7 ? Math.ceil(w / 4) * Math.ceil(h / 4) * z * 16 : w * h * z * 4;
    let data = l.levelData;
    stored += data.byteLength;
    if (plainFile) {
      if (l.uncompressedByteLength !== n) problems.push(`level ${i}: uncompressedByteLength ${l.uncompressedByteLength}, expected ${n}`);
      try {
        data = zstd.decode(data, l.uncompressedByteLength);
      } catch (e) {
        problems.push(`level ${i}: does not inflate: ${e.message || e}`);
        return;
      }
      inflatedTotal += data.byteLength;
      const p = plain && plain.levels[i];
      if (p && Buffer.compare(Buffer.from(data), Buffer.from(p.levelData)) !== 0) problems.push(`level ${i}: inflated bytes differ from ${plainFile}'s level`);
    }
    if (data.byteLength !== n) problems.push(`level ${i}: ${data.byteLength} bytes, expected ${n}`);
  });
  const zinfo = plainFile ? `, zstd ${stored} bytes of levels inflating to ${inflatedTotal} (= ${plainFile})` : '';
  console.log(`${f}: ktx-parse: ${dims.join('x')}, ${c.levels.length} levels, vkFormat ${c.vkFormat}, ` +
    `premultiplied ${premul}${zinfo}: ${problems.length ? problems.join('; ') : 'ok'}`);
  if (problems.length) bad++;
}
process.exit(bad ? 1 : 0);
