// What the web panel's Node tests (browser_test.js, vision_test.js, editor_test.js,
// protocol_test.js) have in common: a TAP-like log (ok, check, fail); waits with a deadline
// that all end at once when something goes wrong (abort: rilbed exited, a signal); `rilbed
// run --gui` started and its page's URL and token read from its stdout; the npm packages
// and Debian's Chromium; screenshots into the artefacts folder; and run(), which runs a
// test's main, reports, closes the browser, kills rilbed and exits 0 or 1.
//
// Each test is its own process: the log's count, the waits and the abort are this module's.
'use strict';

const { spawn } = require('node:child_process');
const fs = require('node:fs');
const os = require('node:os');
const path = require('node:path');

const CHROMIUM = '/usr/bin/chromium';
const DEADLINE_MS = 30000;  // every wait (the machine may be slow, or under ASan)

// ---------------------------------------------------------------- the log
let checks = 0;
function ok(what) {
  checks += 1;
  console.log(`ok ${checks} - ${what}`);
}

class TestFailure extends Error {}
function fail(message) {
  throw new TestFailure(message);
}
function check(condition, message) {
  if (!condition) fail(message);
}
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// ---------------------------------------------------------------- waiting
// `abort` ends every wait at once (rilbed exited, the socket closed, a signal); the first
// reason is kept.
let aborted = null;
const waiters = new Set();
const found = (value) => value !== undefined && value !== null && value !== false;

// Tries every waitFor's condition again: called whenever something arrives (rilbed's
// output, its exit; a test calls it for what it receives itself).
function poke() {
  for (const w of [...waiters]) {
    let value;
    try {
      value = w.condition();
    } catch (e) {
      w.finish();
      w.reject(e);
      continue;
    }
    if (found(value)) {
      w.finish();
      w.resolve(value);
    }
  }
}
function abort(message) {
  if (aborted) return;
  aborted = message;
  for (const w of [...waiters]) {
    w.finish();
    w.reject(new TestFailure(`${message} while waiting for ${w.what}`));
  }
}

// Resolves with what `condition` (sync) returns once it is something other than undefined,
// null or false, trying it now and at every poke(); fails after `ms`, saying what it
// waited for.
function waitFor(what, condition, ms = DEADLINE_MS) {
  return new Promise((resolve, reject) => {
    if (aborted) {
      reject(new TestFailure(`${aborted} while waiting for ${what}`));
      return;
    }
    const w = { what, condition, resolve, reject };
    const timer = setTimeout(() => {
      waiters.delete(w);
      reject(new TestFailure(`timed out after ${ms / 1000} s waiting for ${what}`));
    }, ms);
    w.finish = () => {
      clearTimeout(timer);
      waiters.delete(w);
    };
    waiters.add(w);
    poke();
  });
}

// Tries `condition` (sync or async: a page's state) every `everyMs` until it returns
// something other than undefined, null or false, and returns that; fails after `ms`,
// saying what it waited for and, if given, what `describe()` says it saw last.
async function poll(what, condition, { ms = DEADLINE_MS, everyMs = 100, describe = null } = {}) {
  const end = Date.now() + ms;
  for (;;) {
    if (aborted) fail(`${aborted} while waiting for ${what}`);
    const value = await condition();
    if (found(value)) return value;
    if (Date.now() > end) {
      let seen = '';
      if (describe) {
        try { seen = ` (last seen: ${await describe()})`; } catch (e) { seen = ` (${e.message})`; }
      }
      fail(`timed out after ${ms / 1000} s waiting for ${what}${seen}`);
    }
    await sleep(everyMs);
  }
}

// ---------------------------------------------------------------- rilbed
function describeExit(e) {
  if (e.error) return e.error.message;
  return e.signal ? `killed by ${e.signal}` : `exit code ${e.code}`;
}

// A child process whose stdout lines are kept and whose stderr's last 40 lines are; its
// exit, unless `exitExpected` was set, aborts every wait.
class Child {
  constructor(label, binary, args) {
    this.label = label;
    this.stdoutLines = [];
    this.stderrTail = [];
    this.exit = null;  // {code, signal} once it exited
    this.exitExpected = false;
    this.proc = spawn(binary, args, { stdio: ['ignore', 'pipe', 'pipe'] });
    this.proc.on('error', (e) => {
      this.exit = { code: null, signal: null, error: e };
      abort(`${label} could not be started (${e.message})`);
    });
    const lineReader = (onLine) => {
      let partial = '';
      return (chunk) => {
        partial += chunk.toString('utf8');
        const parts = partial.split('\n');
        partial = parts.pop();
        for (const l of parts) onLine(l);
        poke();
      };
    };
    this.proc.stdout.on('data', lineReader((l) => this.stdoutLines.push(l)));
    this.proc.stderr.on('data', lineReader((l) => {
      this.stderrTail.push(l);
      if (this.stderrTail.length > 40) this.stderrTail.shift();
    }));
    this.proc.on('exit', (code, signal) => {
      this.exit = { code, signal };
      if (!this.exitExpected) abort(`${label} exited unexpectedly (${describeExit(this.exit)})`);
      poke();
    });
  }
  // Ends it (SIGTERM, then SIGKILL after 5 s) unless it has exited.
  async kill() {
    if (this.exit || !this.proc.pid) return;
    this.exitExpected = true;
    const exited = new Promise((resolve) => this.proc.once('exit', resolve));
    this.proc.kill('SIGTERM');
    const timer = setTimeout(() => this.proc.kill('SIGKILL'), 5000);
    await exited;
    clearTimeout(timer);
  }
  tails() {
    const out = this.stdoutLines.slice(-20).join('\n');
    const err = this.stderrTail.join('\n');
    return `--- ${this.label}'s stdout (last lines) ---\n${out}\n--- ${this.label}'s stderr (last lines) ---\n${err}\n---`;
  }
}

// Starts `BINARY run SCENARIO --realtime --duration DURATION --gui --gui-port 0 --out
// STATE.TMP/DIR` (in state.children, killed by run()), waits for the page's URL on its
// stdout and returns {child, runDir, url, port, token}. `label` names it in the messages.
async function startRilbed(state, binary, scenario, { label = 'rilbed', dir = label, duration = 300 } = {}) {
  const runDir = path.join(state.tmp, dir);
  const args = ['run', scenario, '--realtime', '--duration', String(duration), '--gui', '--gui-port', '0', '--out', runDir];
  console.log(`# starting ${binary} ${args.join(' ')}`);
  const child = new Child(label, binary, args);
  state.children.push(child);
  const urlPattern = /(http:\/\/127\.0\.0\.1:(\d+)\/\?token=([^\s&#]+))/;
  const [, url, port, token] = await waitFor(`the line with http://127.0.0.1:PORT/?token=TOKEN on ${label}'s stdout`,
    () => child.stdoutLines.map((l) => urlPattern.exec(l)).find((m) => m));
  return { child, runDir, url, port: Number(port), token };
}

// ---------------------------------------------------------------- the command line, files
// The arguments as `usage` names them ("RILBED SCENARIO [ARTEFACT_DIR]"); one of those
// not in brackets missing: the usage, and exit code 2.
function commandLine(usage) {
  const args = process.argv.slice(2);
  const required = usage.split(' ').filter((w) => !w.startsWith('[')).length;
  for (let i = 0; i < required; i++) {
    if (!args[i]) {
      console.error(`usage: node ${path.basename(require.main.filename)} ${usage}`);
      process.exit(2);
    }
  }
  return args;
}
function checkBinary(binary) {
  check(fs.existsSync(binary), `no rilbed binary at ${binary} (build it first: ./run build)`);
}
function checkScenario(file) {
  check(fs.existsSync(file), `no scenario at ${file}`);
}

// A temp folder for the runs (state.tmp): removed by run() if the test passes, kept if not.
function tempFolder(state, name) {
  state.tmp = fs.mkdtempSync(path.join(os.tmpdir(), `rilbed-web-${name}-`));
  return state.tmp;
}

// A copy of a scenario's text with its `robots:` section replaced by `robots` (YAML text
// starting with "robots:"): its field, timing, camera and safety as shipped.
function withRobots(text, robots) {
  const lines = text.split('\n');
  const start = lines.findIndex((l) => /^robots\s*:/.test(l));
  check(start >= 0, 'the mixed scenario has no robots: section');
  let end = start + 1;
  while (end < lines.length && (/^\s/.test(lines[end]) || lines[end] === '' || /^#/.test(lines[end]))) end++;
  return [...lines.slice(0, start), robots, ...lines.slice(end)].join('\n');
}

// ---------------------------------------------------------------- the npm packages, Chromium
// `name` from web/tests/node_modules; fails saying that ./run test installs it.
function requirePackage(name) {
  const modules = path.join(__dirname, 'node_modules');
  const missing = `${modules} is missing or incomplete: run ./run test (it installs the npm packages)`;
  if (!fs.existsSync(modules)) fail(missing);
  try {
    return require(name);
  } catch (e) {
    return fail(`${missing} (${e.message})`);
  }
}
function requirePlaywright() {
  const playwright = requirePackage('playwright-core');
  if (!fs.existsSync(CHROMIUM)) fail(`no ${CHROMIUM}: run ./run test (it installs Debian's chromium)`);
  return playwright;
}

// Debian's Chromium (state.browser, closed by run()); we run as root: --no-sandbox.
async function launchBrowser(state, playwright) {
  state.browser = await playwright.chromium.launch({ executablePath: CHROMIUM, args: ['--no-sandbox'], timeout: DEADLINE_MS });
  return state.browser;
}
// A browser context whose every action has the deadline.
async function newContext(state, options) {
  const context = await state.browser.newContext(options);
  context.setDefaultTimeout(DEADLINE_MS);
  return context;
}

// A page on `url` (rilbed's, with its token) whose console errors, uncaught exceptions
// and crash are collected in state.pageErrors, once it has connected and shows the run.
// `prepare(page)`, if given, is called before the page loads (the test's own listeners).
async function openPage(state, context, label, url, prepare = null) {
  const page = await context.newPage();
  page.on('console', (m) => {
    if (m.type() === 'error') {
      const where = m.location() && m.location().url ? ` at ${m.location().url}:${m.location().lineNumber}` : '';
      state.pageErrors.push(`${label}: console error: ${m.text()}${where}`);
    }
  });
  page.on('pageerror', (e) => state.pageErrors.push(`${label}: uncaught: ${e.stack || e.message}`));
  page.on('crash', () => state.pageErrors.push(`${label}: the page crashed`));
  if (prepare) prepare(page);
  const response = await page.goto(url, { timeout: DEADLINE_MS });
  check(response && response.status() === 200, `${label}: GET ${url} answered ${response && response.status()}`);
  await poll(`${label} to connect and show the run (connection pill "connected", world, status and poses received)`,
    () => page.evaluate(() => document.getElementById('connection').textContent === 'connected' &&
      window.rilbed && window.rilbed.run.world && window.rilbed.run.status && window.rilbed.run.poses && true),
    { describe: () => page.evaluate(() => `connection "${document.getElementById('connection').textContent}", ` +
      `world ${!!window.rilbed?.run.world}, status ${!!window.rilbed?.run.status}, poses ${!!window.rilbed?.run.poses}`) });
  return page;
}

// ---------------------------------------------------------------- screenshots
// Screenshots go to $RILBED_ARTIFACTS, else `arg` (the test's ARTEFACT_DIR: CTest passes
// BUILD/web-artifacts), else a temp folder, as PREFIX-NAME.png. `fresh`: the previous
// run's PREFIX-*.png removed and the folder said.
function useArtefacts(state, arg, prefix, { fresh = true } = {}) {
  state.artifacts = process.env.RILBED_ARTIFACTS || arg || fs.mkdtempSync(path.join(os.tmpdir(), 'rilbed-web-artifacts-'));
  state.shotPrefix = prefix;
  fs.mkdirSync(state.artifacts, { recursive: true });
  if (fresh) {
    const previous = new RegExp(`^${prefix}-.*\\.png$`);
    for (const f of fs.readdirSync(state.artifacts)) {
      if (previous.test(f)) fs.rmSync(path.join(state.artifacts, f));
    }
    console.log(`# screenshots go to ${state.artifacts}`);
  }
  return state.artifacts;
}

async function screenshot(state, page, name) {
  const file = path.join(state.artifacts, `${state.shotPrefix}-${name}.png`);
  await page.screenshot({ path: file, fullPage: true });
  state.screenshots.push(file);
  console.log(`# screenshot ${file}`);
}

// ---------------------------------------------------------------- the run
// Runs `main(state)` and exits: 0 if it returned, 1 if it threw (or the watchdog fired),
// saying why, with the pages' errors and the end of every child's output, after a
// screenshot of every page still open. It closes the browser, kills the children and
// removes state.tmp (kept on failure). `summary(passed, failed, seconds)` is the last line
// (none if it returns null); `teardown(state)` comes first (the test's own connections).
// SIGINT and SIGTERM abort every wait.
async function run(main, {
  name,
  watchdogMs = 0,
  summary = (passed, failed, seconds) => `${passed} passed, ${failed} failed (${seconds} s)`,
  teardown = null,
}) {
  for (const signal of ['SIGINT', 'SIGTERM']) {
    process.on(signal, () => abort(`${name} got ${signal}`));
  }
  const state = { children: [], pageErrors: [], screenshots: [] };
  const report = (line) => { if (line) console.log(line); };
  let failure = null;
  const watchdog = watchdogMs ? setTimeout(() => {
    const message = `${name} ran longer than ${watchdogMs / 1000} s`;
    abort(message);
    console.error(`${name}: FAIL: ${message}`);
    for (const c of state.children) if (!c.exit) c.proc.kill('SIGKILL');
    process.exit(1);
  }, watchdogMs) : null;
  const started = Date.now();
  const seconds = () => ((Date.now() - started) / 1000).toFixed(1);
  try {
    await main(state);
  } catch (e) {
    failure = e;
  }
  if (teardown) await teardown(state);
  if (failure && state.browser && state.artifacts) {
    // What the pages looked like when it failed.
    for (const context of state.browser.contexts()) {
      for (const [i, p] of context.pages().entries()) {
        try { await screenshot(state, p, `failure-${state.browser.contexts().indexOf(context)}-${i}`); } catch (_) { /* closed */ }
      }
    }
  }
  if (state.browser) await Promise.race([state.browser.close().catch(() => {}), sleep(10000)]);
  clearTimeout(watchdog);
  if (failure) {
    const message = failure instanceof TestFailure ? failure.message : (failure.stack || String(failure));
    console.error(`${name}: FAIL: ${message}`);
    if (state.pageErrors.length) console.error(`${name}: the pages' errors so far:\n  ${state.pageErrors.join('\n  ')}`);
    for (const child of state.children) {
      console.error(child.tails());
      await child.kill();
    }
    if (state.tmp) {
      console.error(`${name}: ${state.children.length > 1 ? 'the runs\' folders are' : 'the run\'s folder is'} kept in ${state.tmp}`);
    }
    report(summary(checks, 1, seconds()));
    process.exit(1);
  }
  for (const child of state.children) await child.kill();
  if (state.screenshots.length) console.log(`# screenshots: ${state.screenshots.join(' ')}`);
  if (state.tmp) fs.rmSync(state.tmp, { recursive: true, force: true });
  report(summary(checks, 0, seconds()));
  process.exit(0);
}

module.exports = {
  CHROMIUM, DEADLINE_MS,
  ok, check, fail, TestFailure, sleep,
  poke, abort, waitFor, poll,
  describeExit, startRilbed,
  commandLine, checkBinary, checkScenario, tempFolder, withRobots,
  requirePackage, requirePlaywright, launchBrowser, newContext, openPage,
  useArtefacts, screenshot,
  run,
};
