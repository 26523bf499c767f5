// Validates glTF files with the Khronos glTF validator (npm package gltf-validator); run by
// `cargo xtask validate-gltf`, which installs it. Prints each file's counts and every error and
// warning; exits 1 if any file has an error.
const validator = require('gltf-validator');
const fs = require('fs');
const path = require('path');
(async () => {
  let failed = 0;
  for (const file of process.argv.slice(2)) {
    const dir = path.dirname(file);
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: file,
      externalResourceFunction: (uri) => new Promise((resolve, reject) => {
        fs.readFile(path.join(dir, decodeURIComponent(uri)), (err, data) => err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages.filter((m) => m.severity <= 1)) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer || ''}: ${m.message}`);
    if (i.numErrors > 0) failed++;
  }
  process.exit(failed ? 1 : 0);
})();
