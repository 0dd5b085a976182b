// Runs the Khronos glTF validator over one .glb and prints its summary and every message.
//   node validate_gltf.js FILE.glb
// Exit 0 when the report has no error; 1 otherwise (or when the file cannot be validated).
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const file = process.argv[2];
const severities = ['error', 'warning', 'info', 'hint'];

async function main() {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,  // no limit
    // A .glb holds everything; any external resource is a fault of the export.
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri}`)),
  });
  const issues = report.issues;
  console.log(`gltf: validator ${report.validatorVersion}: ${issues.numErrors} errors, ` +
              `${issues.numWarnings} warnings, ${issues.numInfos} infos, ${issues.numHints} hints`);
  const info = report.info || {};
  console.log(`gltf: ${info.version} ${info.generator}; animations ${info.animationCount}, ` +
              `skins ${info.hasSkins}, vertices ${info.totalVertexCount}, triangles ${info.totalTriangleCount}`);
  for (const m of issues.messages)
    console.log(`gltf: ${severities[m.severity] || m.severity} ${m.code} at ${m.pointer || m.offset}: ${m.message}`);
  if (issues.numErrors > 0) {
    console.error(`gltf: FAILED: the validator reports ${issues.numErrors} errors in ${file}`);
    process.exit(1);
  }
}

main().catch((e) => {
  console.error(`gltf: FAILED: could not validate ${file}: ${e && e.stack ? e.stack : e}`);
  process.exit(1);
});
