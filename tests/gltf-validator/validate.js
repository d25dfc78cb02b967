// Print the Khronos glTF-Validator report of each file given as JSON:
// one report for one file, an array of reports for several.
// Install: npm ci --prefix tests/gltf-validator
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  return validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 1000,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
}

async function main() {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error("usage: node validate.js FILE.glb [FILE ...]");
    process.exit(2);
  }
  const reports = [];
  for (const file of files) reports.push(await validate(file));
  console.log(JSON.stringify(files.length === 1 ? reports[0] : reports, null, 1));
}

main().catch((err) => {
  console.error(String(err));
  process.exit(1);
});
