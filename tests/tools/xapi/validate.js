// Validates a file of xAPI statements (a JSON array, or one statement) with Learning Locker's
// conformance-tested validator. Prints each problem with its statement index and path; exits 1
// when any statement has one, 2 when the file cannot be read. Used by tests/engine/records.
'use strict';
const fs = require('fs');
const validate = require('@learninglocker/xapi-validation').default;

let statements;
try {
  statements = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
} catch (e) {
  console.error(`cannot read ${process.argv[2]}: ${e.message}`);
  process.exit(2);
}
if (!Array.isArray(statements)) statements = [statements];
let problems = 0;
statements.forEach((s, i) => {
  for (const w of validate(s)) {
    ++problems;
    console.log(`statement ${i}: ${w.path.join('.')}: ${w.message} (${JSON.stringify(w.data)})`);
  }
});
console.log(`${statements.length} statement(s), ${problems} problem(s)`);
process.exit(problems === 0 ? 0 : 1);
