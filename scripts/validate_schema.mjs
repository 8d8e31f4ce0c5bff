// Dev-only: validate JSON files against a JSON Schema (draft 2020-12) with Ajv.
// Usage: node scripts/validate_schema.mjs SCHEMA FILE...
// Prints one line per file, `ok` or its first errors as JSON; exits 0 unless the
// schema itself does not compile.
import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
const require = createRequire(import.meta.url);
const Ajv2020 = require("ajv/dist/2020").default;

const [schemaPath, ...files] = process.argv.slice(2);
// strict: the schema must use only known keywords; `format`s such as `double` and
// `uint` (schemars' annotations) are not asserted
const ajv = new Ajv2020({ strict: true, validateFormats: false, allErrors: false });
const validate = ajv.compile(JSON.parse(readFileSync(schemaPath, "utf8")));
for (const f of files) {
  const ok = validate(JSON.parse(readFileSync(f, "utf8")));
  console.log(ok ? `${f}: ok` : `${f}: ${JSON.stringify(validate.errors.slice(0, 3))}`);
}
