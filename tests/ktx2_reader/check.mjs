// Reads .ktx2 files with ktx-parse (the KTX2 reader of three.js's KTX2Loader and
// glTF-Transform) and checks what billow promises of its 3D-texture exports: one face, no
// array layers, no supercompression, RGBA8 (sRGB or linear, matching the DFD's transfer
// function), the premultiplied flag in the DFD, and a full MIP chain whose level sizes match
// the halved dimensions; or the same as BC7 blocks (BC7_SRGB_BLOCK / BC7_UNORM_BLOCK, DFD colour
// model BC7, each level 16 bytes per 4x4 block of each z slice: billow voxelize --compress bc,
// the default). Used by `make check-ktx2`; exits 1 on a mismatch, 2 when it cannot run.
// Usage: node check.mjs MODULE_DIR FILE...
import fs from 'fs';
import path from 'path';
import { pathToFileURL } from 'url';

const [moduleDir, ...files] = process.argv.slice(2);
let ktx;
try {
  ktx = await import(pathToFileURL(path.join(moduleDir, 'ktx-parse', 'dist', 'index.mjs')).href);
} catch (e) {
  console.error(`check.mjs: ktx-parse not found under ${moduleDir} (make check-ktx2 installs it)`);
  process.exit(2);
}
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
  if (c.supercompressionScheme !== 0) problems.push(`supercompression ${c.supercompressionScheme}`);
  if (!(c.pixelDepth > 0)) problems.push('not a 3D texture');
  const dims = [c.pixelWidth, c.pixelHeight, c.pixelDepth];
  const full = 1 + Math.floor(Math.log2(Math.max(...dims)));
  if (c.levels.length !== full) problems.push(`${c.levels.length} levels, a full chain has ${full}`);
  c.levels.forEach((l, i) => {
    const [w, h, z] = dims.map((x) => Math.max(1, x >> i));
    const n = bc7 ? Math.ceil(w / 4) * Math.ceil(h / 4) * z * 16 : w * h * z * 4;
    if (l.levelData.byteLength !== n) problems.push(`level ${i}: ${l.levelData.byteLength} bytes, expected ${n}`);
  });
  console.log(`${f}: ktx-parse: ${dims.join('x')}, ${c.levels.length} levels, vkFormat ${c.vkFormat}, ` +
    `premultiplied ${premul}: ${problems.length ? problems.join('; ') : 'ok'}`);
  if (problems.length) bad++;
}
process.exit(bad ? 1 : 0);
