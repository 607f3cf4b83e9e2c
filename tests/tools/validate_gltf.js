// node validate_gltf.js FILE...: the Khronos glTF validator (npm gltf-validator) on each file;
// prints the counts and every error and warning, exits 1 when any file has an error.
const validator = require('gltf-validator');
const fs = require('fs');
const path = require('path');
(async () => {
  let errors = 0;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file), maxIssues: 200,
      externalResourceFunction: (uri) => new Promise((resolve, reject) => {
        fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)), (err, data) => err ? reject(err) : resolve(new Uint8Array(data)));
      })});
    const n = report.issues;
    console.log(`${file}: ${n.numErrors} errors, ${n.numWarnings} warnings, ${n.numInfos} infos`);
    for (const m of n.messages) if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code}: ${m.message} (${m.pointer || ''})`);
    errors += n.numErrors;
  }
  process.exit(errors > 0 ? 1 : 0);
})().catch((e) => { console.error(e); process.exit(2); });
