// Validates a .glb with the Khronos glTF validator; prints {"errors", "warnings", "nodes", "messages"}.
const fs = require('fs');
const path = require('path');
const validator = require(path.join(__dirname, '../../.validators/node_modules/gltf-validator'));
const file = process.argv[2];
const bytes = new Uint8Array(fs.readFileSync(file));
validator.validateBytes(bytes, { maxIssues: 100 }).then((report) => {
  const glb = Buffer.from(bytes);
  const jsonLength = glb.readUInt32LE(12);
  const doc = JSON.parse(glb.subarray(20, 20 + jsonLength).toString('utf8'));
  console.log(JSON.stringify({
    errors: report.issues.numErrors,
    warnings: report.issues.numWarnings,
    nodes: (doc.nodes || []).map((n) => n.name),
    messages: report.issues.messages.slice(0, 10).map((m) => `${m.code} ${m.message} ${m.pointer || ''}`),
  }));
}).catch((e) => { console.error(e); process.exit(2); });
