// Dev-only: validate .glb files with the Khronos glTF-Validator (npm ci first).
// Usage: node scripts/validate_gltf.mjs FILE...   Prints one JSON line per file;
// exits 1 if any file has an error or a warning.
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
const require = createRequire(import.meta.url);
const validator = require("gltf-validator");

let bad = 0;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    maxIssues: 0,
    writeTimestamp: false,
  });
  const { numErrors, numWarnings, numInfos, messages } = report.issues;
  if (numErrors > 0 || numWarnings > 0) bad += 1;
  console.log(JSON.stringify({ file, numErrors, numWarnings, numInfos, messages: messages.slice(0, 10) }));
}
process.exit(bad > 0 ? 1 : 0);
