// Validate one glTF 2.0 asset (.glb, or .gltf with its buffers beside it) with the
// Khronos glTF validator and print its JSON report on stdout.
//
//   node validate.mjs FILE
//
// Exit status: 0 the validator ran (whatever it found: read report.issues.numErrors);
// 1 the file could not be read or the validator refused it (the reason on stderr);
// 2 usage. External resources (a .gltf's buffers) are read relative to FILE.
import { readFile } from "node:fs/promises";
import path from "node:path";
import validator from "gltf-validator";

const [file] = process.argv.slice(2);
if (!file) {
  console.error("usage: node validate.mjs FILE");
  process.exit(2);
}

try {
  const asset = await readFile(file);
  const report = await validator.validateBytes(new Uint8Array(asset), {
    uri: path.basename(file),
    // Report every issue: the Python side counts them by severity.
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))),
  });
  process.stdout.write(JSON.stringify(report, null, 2) + "\n");
} catch (error) {
  console.error(`${file}: ${error}`);
  process.exit(1);
}
