#!/usr/bin/env node
// ESLint over the web panel's JavaScript (web/*.js, web/tests/), with eslint.config.js
// beside this file, from any folder:
//
//   node web/tests/lint.js
//
// Prints each problem (eslint's stylish format) and a closing line; exits 0 when there is
// none, 1 when there is one (a warning too), 2 when eslint is not installed, saying that
// ./run test installs it. CTest runs it as web_lint (label web).
'use strict';

const fs = require('node:fs');
const path = require('node:path');

const WEB = path.resolve(__dirname, '..');
const CONFIG = path.join(__dirname, 'eslint.config.js');

// eslint, and the packages eslint.config.js takes its rules and globals from.
function requireEslint() {
  const modules = path.join(__dirname, 'node_modules');
  const missing = `${modules} is missing or incomplete: run ./run test (it installs the npm packages of web/tests)`;
  if (!fs.existsSync(modules)) return { missing };
  try {
    for (const name of ['@eslint/js', 'globals']) require.resolve(name);
    return { eslint: require('eslint') };
  } catch (e) {
    return { missing: `${missing} (${e.message.split('\n')[0]})` };
  }
}

async function main() {
  const { eslint, missing } = requireEslint();
  if (!eslint) {
    console.error(`web_lint: FAIL: ${missing}`);
    return 2;
  }
  // The config's patterns are relative to web/: eslint runs there, wherever it was started.
  const linter = new eslint.ESLint({ cwd: WEB, overrideConfigFile: CONFIG, errorOnUnmatchedPattern: true });
  const results = await linter.lintFiles(['.']);
  const formatter = await linter.loadFormatter('stylish');
  const report = await formatter.format(results);
  if (report) console.log(report);
  const errors = results.reduce((n, r) => n + r.errorCount, 0);
  const warnings = results.reduce((n, r) => n + r.warningCount, 0);
  const verdict = errors + warnings ? 'FAIL' : 'PASS';
  console.log(`web_lint: ${verdict}: eslint ${eslint.ESLint.version}, ${results.length} files, ${errors} errors, ${warnings} warnings`);
  return errors + warnings ? 1 : 0;
}

main().then((code) => { process.exitCode = code; }, (e) => {
  console.error(`web_lint: FAIL: ${e.stack || e.message}`);
  process.exitCode = 1;
});
