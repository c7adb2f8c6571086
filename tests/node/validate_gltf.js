// node validate_gltf.js FILE...: runs the Khronos glTF validator on each file (.gltf with its .bin beside it, or
// .glb) and prints one JSON object per file on stdout: {"file", "errors", "warnings", "infos", "hints", "messages"}.
// Exit status 0 when it could validate every file (the caller judges the counts), 1 otherwise.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validate(file) {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    maxIssues: 200,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        // Only files beside the asset: a URI that climbs out is a failure of the writer, not something to read.
        const resolved = path.resolve(path.dirname(file), decodeURIComponent(uri));
        if (path.dirname(resolved) !== path.resolve(path.dirname(file))) reject(new Error('outside: ' + uri));
        else fs.readFile(resolved, (err, data) => (err ? reject(err) : resolve(new Uint8Array(data))));
      }),
  });
  const issues = report.issues;
  return {
    file,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages: issues.messages.map((m) => `${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code}: ${m.message} (${m.pointer || m.offset || ''})`),
  };
}

(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    try {
      console.log(JSON.stringify(await validate(file)));
    } catch (e) {
      console.error(`validate_gltf: ${file}: ${e.message || e}`);
      failed = true;
    }
  }
  process.exit(failed ? 1 : 0);
})();
