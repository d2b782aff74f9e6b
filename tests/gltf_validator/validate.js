// Validates .glb files with the Khronos glTF-Validator (npm package `gltf-validator`);
// used by `make check-gltf`. Prints one line per file and every issue; exits 1 when a
// file has an error or a warning, 2 when the validator cannot run.
const fs = require('fs');
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error('validate.js: the gltf-validator package is not installed (make check-gltf installs it)');
  process.exit(2);
}
(async () => {
  let bad = 0;
  for (const f of process.argv.slice(2)) {
    const r = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)), { maxIssues: 100 });
    const i = r.issues;
    console.log(`${f}: glTF-Validator ${validator.version()}: ${i.numErrors} errors, ` +
      `${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
    for (const m of i.messages) console.log(`  ${m.severity} ${m.code} ${m.pointer || ''} ${m.message}`);
    if (i.numErrors > 0 || i.numWarnings > 0) bad++;
  }
  process.exit(bad ? 1 : 0);
})().catch((e) => { console.error('validate.js:', e.message || e); process.exit(2); });
