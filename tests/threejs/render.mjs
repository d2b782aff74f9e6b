// Renders the default scene of a .glb with three.js (GLTFLoader) in headless Chromium
// (playwright-core driving Debian's chromium, WebGL on SwiftShader) and writes a PNG.
//
//   node render.mjs --modules DIR --glb FILE --out PNG --eye X,Y,Z --target X,Y,Z
//        --fov DEG --size WxH [--light X,Y,Z --ambient A] [--chromium PATH]
//
// DIR holds node_modules/three and node_modules/playwright-core (or is a colon-separated
// list of such folders). Offline: the page, the three.js modules and the .glb are served
// by a static server on 127.0.0.1 that this script starts; Chromium is told not to reach
// anything else.
//
// What is drawn: PerspectiveCamera(fov = vertical FOV, aspect W/H) at eye looking at
// target, y up (three.js and billow share these conventions), transparent background,
// outputColorSpace SRGB, no tone mapping, MSAA off, pixel ratio 1. Unlit glTF materials
// (KHR_materials_unlit: the billboards, lighting baked in) are drawn as GLTFLoader made
// them (MeshBasicMaterial). Lit materials (the trunk) become MeshLambertMaterial (same
// colour, texture, alpha mode and sidedness) under an ambient light A and a directional
// light 1 − A towards --light, each × π (three.js's Lambert BRDF is albedo / π): albedo ·
// (A + (1 − A)·max(0, N·L)), the model billow's bake and CPU renderer use.
import http from 'node:http';
import fs from 'node:fs';
import path from 'node:path';
import os from 'node:os';
import { createRequire } from 'node:module';

function die(msg) {
  console.error(`error: render.mjs: ${msg}`);
  process.exit(1);
}

const args = {};
for (let i = 2; i < process.argv.length; i += 2) {
  const k = process.argv[i];
  const v = process.argv[i + 1];
  if (!k.startsWith('--') || v === undefined) die(`bad argument ${k}`);
  args[k.slice(2)] = v;
}
for (const k of ['modules', 'glb', 'out', 'eye', 'target', 'fov', 'size']) {
  if (!(k in args)) die(`--${k} is required`);
}
const vec3 = (k) => {
  const v = args[k].split(',').map(Number);
  if (v.length !== 3 || !v.every(Number.isFinite)) die(`--${k} '${args[k]}': expected X,Y,Z`);
  return v;
};
const [W, H] = args.size.split('x').map(Number);
if (!(W > 0 && H > 0)) die(`--size '${args.size}': expected WxH`);
const params = {
  eye: vec3('eye'),
  target: vec3('target'),
  fov: Number(args.fov),
  width: W,
  height: H,
  light: args.light ? vec3('light') : null,
  ambient: args.ambient === undefined ? 1 : Number(args.ambient),
};

// Locate a package folder among the module roots.
const roots = args.modules.split(':').map((r) => path.resolve(r));
function pkg(name) {
  for (const r of roots) {
    const p = path.join(r, 'node_modules', name);
    if (fs.existsSync(path.join(p, 'package.json'))) return p;
  }
  die(`${name} not found under ${roots.join(', ')}`);
}
const threeDir = pkg('three');
const pwDir = pkg('playwright-core');
const { chromium } = createRequire(import.meta.url)(pwDir);

const PAGE = `<!doctype html>
<html><head><meta charset="utf-8">
<script type="importmap">
{"imports": {"three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/"}}
</script>
<style>html, body { margin: 0; background: transparent; }</style>
</head><body><canvas id="c"></canvas>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
window.render = async (p) => {
  const canvas = document.getElementById('c');
  const renderer = new THREE.WebGLRenderer({
    canvas, alpha: true, antialias: false, preserveDrawingBuffer: true, premultipliedAlpha: true,
  });
  renderer.setPixelRatio(1);
  renderer.setSize(p.width, p.height, false);
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.setClearColor(0x000000, 0);
  const gltf = await new GLTFLoader().loadAsync('/model.glb');
  const scene = gltf.scene;
  let unlit = 0, lit = 0;
  scene.traverse((o) => {
    if (!o.isMesh) return;
    const mats = Array.isArray(o.material) ? o.material : [o.material];
    const out = mats.map((m) => {
      if (m.isMeshBasicMaterial) { unlit++; return m; }
      lit++;
      return new THREE.MeshLambertMaterial({
        color: m.color, map: m.map, alphaTest: m.alphaTest, transparent: m.transparent,
        side: m.side, vertexColors: m.vertexColors, depthWrite: m.depthWrite,
      });
    });
    o.material = Array.isArray(o.material) ? out : out[0];
  });
  if (p.light) {
    scene.add(new THREE.AmbientLight(0xffffff, Math.PI * p.ambient));
    const d = new THREE.DirectionalLight(0xffffff, Math.PI * (1 - p.ambient));
    d.position.set(...p.light);
    scene.add(d);
    scene.add(d.target);
  }
  const camera = new THREE.PerspectiveCamera(p.fov, p.width / p.height, 0.01, 1000);
  camera.position.set(...p.eye);
  camera.up.set(0, 1, 0);
  camera.lookAt(...p.target);
  const box = new THREE.Box3().setFromObject(scene);
  const r = box.getSize(new THREE.Vector3()).length();
  const dist = camera.position.distanceTo(box.getCenter(new THREE.Vector3()));
  camera.near = Math.max(1e-3 * (dist + r), dist - r);
  camera.far = 2 * (dist + r);
  camera.updateProjectionMatrix();
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  return {
    png: canvas.toDataURL('image/png'),
    renderer: gl.getParameter(gl.getExtension('WEBGL_debug_renderer_info')?.UNMASKED_RENDERER_WEBGL ?? gl.RENDERER),
    unlit, lit, three: THREE.REVISION,
  };
};
window.ready = true;
</script></body></html>`;

const types = { '.js': 'text/javascript', '.html': 'text/html', '.glb': 'model/gltf-binary' };
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(new URL(req.url, 'http://x').pathname);
  let file = null;
  if (url === '/favicon.ico') {
    res.writeHead(204);
    return res.end();
  }
  if (url === '/' || url === '/index.html') {
    res.writeHead(200, { 'content-type': 'text/html' });
    return res.end(PAGE);
  } else if (url === '/model.glb') {
    file = args.glb;
  } else if (url.startsWith('/three/')) {
    file = path.join(threeDir, path.normalize(url.slice('/three/'.length)));
    if (!file.startsWith(threeDir + path.sep)) file = null;
  }
  if (!file || !fs.existsSync(file) || !fs.statSync(file).isFile()) {
    res.writeHead(404);
    return res.end();
  }
  res.writeHead(200, { 'content-type': types[path.extname(file)] ?? 'application/octet-stream' });
  fs.createReadStream(file).pipe(res);
});
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const base = `http://127.0.0.1:${server.address().port}`;

const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'billow-threejs-'));
let browser;
let code = 0;
try {
  // A fresh profile (--user-data-dir, which playwright takes as this first argument).
  browser = await chromium.launchPersistentContext(profile, {
    executablePath: args.chromium ?? '/usr/bin/chromium',
    headless: true,
    args: [
      '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
      '--disable-quic', '--no-first-run', '--disable-component-update', '--disable-sync',
      '--enable-unsafe-swiftshader',
    ],
    viewport: { width: W, height: H },
    timeout: 60000,
  });
  const page = browser.pages()[0] ?? (await browser.newPage());
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(base + '/', { timeout: 60000 });
  await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
  const r = await page.evaluate((p) => window.render(p), params);
  if (errors.length) console.error(`render.mjs: page said: ${errors.join(' | ')}`);
  const png = Buffer.from(r.png.replace(/^data:image\/png;base64,/, ''), 'base64');
  const tmp = `${args.out}.tmp`;
  fs.writeFileSync(tmp, png);
  fs.renameSync(tmp, args.out);
  console.log(`${args.out}: three.js r${r.three} on ${r.renderer}: ${r.unlit} unlit and ${r.lit} lit materials, ${W}x${H}`);
} catch (e) {
  console.error(`error: render.mjs: ${e.message.split('\n')[0]}`);
  code = 1;
} finally {
  if (browser) await browser.close();
  server.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
process.exit(code);
