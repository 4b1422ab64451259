// Validates glTF binary files with the Khronos glTF validator (npm
// gltf-validator, installed into build/npm by tests/gltf/validate.sh).
//   node tests/gltf/validate.js FILE.glb ...
// Prints each file's counts of errors, warnings, infos and hints and every
// error and warning; exits 1 if any file has an error.
const fs = require("fs");
const validator = require(process.env.GLTF_VALIDATOR || "gltf-validator");
(async () => {
    let bad = 0;
    for (const file of process.argv.slice(2)) {
        const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { maxIssues: 100 });
        const is = report.issues;
        console.log(`${file}: ${is.numErrors} errors, ${is.numWarnings} warnings, ${is.numInfos} infos, ${is.numHints} hints`);
        for (const m of is.messages)
            if (m.severity <= 1) console.log(`  ${m.severity === 0 ? "error" : "warning"} ${m.code} ${m.pointer || ""}: ${m.message}`);
        if (is.numErrors > 0) bad = 1;
    }
    process.exit(bad);
})().catch((e) => { console.error(e); process.exit(2); });
