// ESLint over the web panel (web/tests/lint.js, CTest's web_lint): the page's ES modules
// in web/ with the browser's globals, the Node tests in web/tests/ with Node's. The
// packages live in web/tests/node_modules, so this file lives beside them; its patterns
// are relative to web/, where lint.js runs eslint (by hand: from web/,
// `node tests/node_modules/eslint/bin/eslint.js --config tests/eslint.config.js .`).
'use strict';

const path = require('node:path');
const js = require('@eslint/js');
const globals = require('globals');

const WEB = path.resolve(__dirname, '..');

// Beyond the recommended set: rules that catch bugs, not matters of taste.
const bugCatchers = {
  eqeqeq: ['error', 'always', { null: 'ignore' }],             // `==` coerces: '' == 0
  'no-var': 'error',                                             // function-scoped, hoisted: a loop's closures share it
  'no-use-before-define': ['error', { functions: false, classes: true, variables: false }], // the temporal dead zone
  'no-self-compare': 'error',
  'no-template-curly-in-string': 'error',                        // '${x}' meant as `${x}`
  'no-unmodified-loop-condition': 'error',
  'no-unreachable-loop': 'error',
  'no-sequences': 'error',                                       // a comma where && or ; was meant
  'no-return-assign': ['error', 'except-parens'],
  'array-callback-return': ['error', { allowImplicit: true }],   // a map() callback that forgets to return
  'no-constructor-return': 'error',
  // An unused variable is a bug or dead code; `_name` says "unused on purpose" (a
  // destructured key left out, an argument a callback must take).
  'no-unused-vars': ['error', { argsIgnorePattern: '^_', varsIgnorePattern: '^_', caughtErrorsIgnorePattern: '^_' }],
};

// The tests that drive a page with Playwright pass it functions (page.evaluate,
// waitForFunction) that run in the browser: those see the browser's globals.
const PAGE_DRIVERS = ['tests/browser_test.js', 'tests/vision_test.js', 'tests/editor_test.js', 'tests/support.js', 'tests/draw_bench.js'];

const recommended = (files, sourceType, globalNames) => ({
  basePath: WEB,
  files,
  languageOptions: { ecmaVersion: 2024, sourceType, globals: globalNames },
  rules: { ...js.configs.recommended.rules, ...bugCatchers },
});

module.exports = [
  { basePath: WEB, ignores: ['**/node_modules/**'] },
  recommended(['*.js'], 'module', globals.browser),
  recommended(['tests/**/*.js'], 'commonjs', globals.node),
  recommended(['tests/**/*.mjs'], 'module', globals.node),
  { basePath: WEB, files: PAGE_DRIVERS, languageOptions: { globals: { ...globals.node, ...globals.browser } } },
  { basePath: WEB, files: ['tests/**/*.js'], rules: { strict: ['error', 'global'] } },
];
