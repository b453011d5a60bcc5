// Runs the Khronos glTF-Validator (npm `gltf-validator`) over glTF files and prints one JSON line
// per file: {"file", "errors", "codes": [the error codes], "messages": [the first few]}.
// External buffers and images are read beside the file, as a loader would.
// Usage: node scripts/gltf-validator.js FILE...   (NODE_PATH must lead to gltf-validator)
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validate(file) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, {
        uri: path.basename(file),
        maxIssues: 200,
        externalResourceFunction: (uri) => new Promise((resolve, reject) => {
            const target = path.resolve(path.dirname(file), decodeURIComponent(uri));
            fs.readFile(target, (error, data) => (error ? reject(error.toString()) : resolve(new Uint8Array(data))));
        }),
    });
    const errors = report.issues.messages.filter((m) => m.severity === 0);
    return {
        file,
        errors: report.issues.numErrors,
        codes: [...new Set(errors.map((m) => m.code))].sort(),
        messages: errors.slice(0, 3).map((m) => `${m.code} ${m.pointer || ''}: ${m.message}`),
    };
}

(async () => {
    for (const file of process.argv.slice(2)) {
        try {
            console.log(JSON.stringify(await validate(file)));
        } catch (error) {
            console.log(JSON.stringify({file, errors: 1, codes: ['UNREADABLE'], messages: [String(error)]}));
        }
    }
})();
