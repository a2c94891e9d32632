#!/usr/bin/env node
// The web panel's scenario editor (web/editor.js) in a real browser: Debian's
// Chromium, driven by playwright-core, against `rilbed run --gui`.
//
//   node web/tests/editor_test.js RILBED [ARTEFACT_DIR]
//
// Runs `RILBED run scenarios/convoy_sim.yaml --realtime --duration 300 --gui --gui-port 0
// --out TMPDIR`, opens the page and checks, with mouse and keys on the editor's canvas:
//   1. "Start from this run" fills the editor with the run's field and its robots at
//      their current poses;
//   2. an obstacle (four clicks, the last a double-click), one of its vertices dragged;
//      a track (three clicks and Enter); a beacon (pressed and dragged to aim it, with
//      the id, aperture and range of the tool's options); a robot (one click, controller
//      wander); robot 3 dragged elsewhere and turned by its handle; robot 5 turned by
//      shift + wheel; robot 8 clicked and deleted with the Delete key;
//   3. Save downloads scenario.yaml, the text the page shows, with every one of those
//      at the place the mouse put it (within 4 mm, 1.5 degrees), and `RILBED run
//      SAVED --fast --duration 2` accepts it (exit 0);
//   4. each scenarios/*.yaml loaded through the file input and saved unchanged parses
//      (js-yaml) to an object deep-equal to the original's, and `RILBED run` accepts it
//      (--fast --duration 1, plus --all-virtual when it has real robots);
//   4b. a scenario of robots of parts (model:, body: as a disc and as an outline,
//      wheels:) loaded and saved unchanged, without problems, accepted by rilbed run; the
//      bodies drawn as themselves and hit by their size;
//   5. a group split by dragging one of its robots out of the tray; 6. "Poses from run";
//   7. the controllers are the server's registry: controllers.json is what `RILBED
//      controllers --json` prints, the new robot's and a robot's controller choices are
//      exactly its names, a robot's form has an input per parameter with the registry's
//      unit, default, range and summary; an out-of-range speed_mps is flagged, a change of
//      controller keeps the params it takes, adds the sensors it requires and asks for its
//      required params; with controllers.json failing (503) the editor says so and offers
//      no controller;
// and that the page logged no console error and threw nothing. Screenshots of the
// editor (editor.png, editor-bodies.png, editor-params.png, editor-no-registry.png) go
// to $RILBED_ARTIFACTS, else ARTEFACT_DIR (CTest passes BUILD/web-artifacts), else a temp
// folder; their paths are printed. Every wait polls with a deadline; on any
// failure it says what it was waiting for, shows the end of rilbed's output, kills
// rilbed and the browser and exits 1. CTest runs it as web_editor (label e2e); `./run
// test` installs its npm packages (web/tests and web/: the page's js-yaml) and Chromium.
'use strict';

const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const assert = require('node:assert');
const {
  CHROMIUM, DEADLINE_MS, ok, check, fail, startRilbed, commandLine, checkBinary, tempFolder, launchBrowser,
  newContext, useArtefacts, run,
} = require('./support');

const WEB = path.resolve(__dirname, '..');
const SCENARIOS = path.resolve(__dirname, '../../scenarios');
const TOLERANCE_M = 0.004;     // a pixel of the canvas is about 2 mm of the field
const TOLERANCE_DEG = 1.5;

// ---------------------------------------------------------------- the npm packages
function requirePackages() {
  const need = [
    [path.join(__dirname, 'node_modules'), 'playwright-core', 'web/tests'],
    [path.join(WEB, 'node_modules'), 'js-yaml', 'web (the page loads js-yaml from web/node_modules)'],
  ];
  const loaded = {};
  for (const [dir, name, where] of need) {
    const missing = `${dir} is missing or incomplete (${name}): run ./run test (it installs the npm packages of ${where})`;
    if (!fs.existsSync(dir)) fail(missing);
    try {
      loaded[name] = require(require.resolve(name, { paths: [path.dirname(dir)] }));
    } catch (e) {
      fail(`${missing} (${e.message})`);
    }
  }
  return { playwright: loaded['playwright-core'], yaml: loaded['js-yaml'] };
}

// `RILBED run FILE ARGS...`, which must exit 0 within the deadline.
function runAccepts(binary, file, args, outDir) {
  const r = spawnSync(binary, ['run', file, ...args, '--quiet', '--out', outDir], { encoding: 'utf8', timeout: 60000 });
  check(r.status === 0, `rilbed run ${path.basename(file)} ${args.join(' ')} ended with ${r.error ? r.error.message : r.signal || `exit code ${r.status}`}:\n` +
    `${(r.stdout || '').slice(-1500)}\n${(r.stderr || '').slice(-1500)}\n--- the file ---\n${fs.readFileSync(file, 'utf8')}`);
}

// ---------------------------------------------------------------- the test
async function main(state) {
  const [binary, artefactArg] = commandLine('RILBED [ARTEFACT_DIR]');
  checkBinary(binary);
  check(fs.existsSync(CHROMIUM), `no ${CHROMIUM}: install Debian's chromium (./run test does)`);
  const { playwright, yaml } = requirePackages();
  tempFolder(state, 'editor');
  useArtefacts(state, artefactArg, 'editor', { fresh: false });

  const { url } = await startRilbed(state, binary, path.join(SCENARIOS, 'convoy_sim.yaml'), { dir: 'run' });
  ok('rilbed serves the page');

  await launchBrowser(state, playwright);
  const context = await newContext(state, { viewport: { width: 1400, height: 1000 }, acceptDownloads: true });
  const page = await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') state.pageErrors.push(`console error: ${m.text()}`); });
  page.on('pageerror', (e) => state.pageErrors.push(`uncaught: ${e.message}`));
  const until = (what, fn, arg) => page.waitForFunction(fn, arg, { timeout: DEADLINE_MS, polling: 50 })
    .then((h) => h.jsonValue())
    .catch((e) => fail(`timed out after ${DEADLINE_MS / 1000} s waiting for ${what} (${e.message.split('\n')[0]})`));
  const doc = () => page.evaluate(() => JSON.parse(JSON.stringify(window.rilbedEditor.doc)));

  await page.goto(url);
  await until('the page to hold the run\'s world and poses, and the editor to start',
    () => window.rilbed?.run?.world && window.rilbed.run.poses?.robots?.length && window.rilbedEditor);
  await page.click('#editor-panel > summary');
  await until('the editor panel to open', () => document.getElementById('editor-panel').open);
  ok('the page shows the run; the editor panel opens');

  // 1. Start from this run.
  // (The click and the poses it took in one go: the run moves on.)
  await page.locator('#editor-from-run').scrollIntoViewIfNeeded();
  const runPoses = await page.evaluate(() => { document.getElementById('editor-from-run').click(); return window.rilbed.run.poses; });
  const started = await until('the editor to hold the run\'s 8 robots at poses',
    () => { const d = window.rilbedEditor.doc; return d.robots?.length === 8 && d.robots.every((r) => Array.isArray(r.pose)) && JSON.parse(JSON.stringify(d)); });
  check(started.field.width_m === 1.5 && started.field.height_m === 1.2, `the editor's field is ${JSON.stringify(started.field)}, not 1.5 x 1.2`);
  for (const r of started.robots) {
    const p = runPoses.robots.find((q) => q.id === r.id);
    // Within 3 mm: poses are saved to the millimetre, and robots that touch in the run are
    // moved apart by up to 2 mm (or the run would refuse the file as overlapping).
    check(p && Math.abs(p.x_m - r.pose[0]) < 0.003 && Math.abs(p.y_m - r.pose[1]) < 0.003,
      `robot ${r.id} is at ${JSON.stringify(r.pose)} in the editor, at ${p && [p.x_m, p.y_m]} in the run's poses (t ${runPoses.t_s})`);
  }
  ok(`"Start from this run": field 1.5 x 1.2 m, robots ${started.robots.map((r) => r.id).join(',')} at the run's poses of t = ${runPoses.t_s.toFixed(1)} s`);

  // The canvas, wholly in view; field metres to page pixels.
  const canvas = page.locator('#editor-canvas');
  await canvas.evaluate((el) => el.scrollIntoView({ block: 'center' }));
  // (Where the canvas is, asked again for every point: nothing should move it, but if
  // something did, the clicks still land where meant.)
  const canvasBox = async () => {
    const b = await canvas.boundingBox();
    check(b && b.y >= 0 && b.y + b.height <= 1000, `the editor's canvas is not wholly in view: ${JSON.stringify(b)}`);
    return b;
  };
  let box = await canvasBox();
  const at = async (x, y) => {
    box = await canvasBox();
    const [u, v] = await page.evaluate(([a, b]) => window.rilbedEditor.project(a, b), [x, y]);
    return [box.x + u, box.y + v];
  };
  const mouse = page.mouse;
  const clickAt = async (x, y) => { const [u, v] = await at(x, y); await mouse.click(u, v); };
  const dragPx = async ([u0, v0], [u1, v1]) => { await mouse.move(u0, v0); await mouse.down(); await mouse.move(u1, v1, { steps: 8 }); await mouse.up(); };

  // Free places: away from every robot and from what the test has put down.
  const taken = started.robots.map((r) => ({ x: r.pose[0], y: r.pose[1], r: 0.03 }));
  const freeSpot = (clearance, what) => {
    for (let y = 0.15; y <= 1.05; y += 0.05) {
      for (let x = 0.15; x <= 1.35; x += 0.05) {
        if (taken.every((t) => Math.hypot(t.x - x, t.y - y) >= clearance + t.r)) return [Math.round(x * 100) / 100, Math.round(y * 100) / 100];
      }
    }
    return fail(`no free place for ${what} among ${JSON.stringify(taken)}`);
  };
  const near = (a, b, tol = TOLERANCE_M) => Math.abs(a - b) <= tol;
  const nearPoint = (p, q) => Array.isArray(p) && near(p[0], q[0]) && near(p[1], q[1]);
  const angleOff = (a, b) => Math.abs(((a - b + 540) % 360) - 180);

  // 2a. An obstacle: a 10 cm square, four clicks (the last a double-click).
  const [ox, oy] = freeSpot(0.16, 'the obstacle');
  taken.push({ x: ox, y: oy, r: 0.13 });
  const square = [[ox - 0.05, oy - 0.05], [ox + 0.05, oy - 0.05], [ox + 0.05, oy + 0.05], [ox - 0.05, oy + 0.05]];
  await page.check('input[name="editor-tool"][value="obstacle"]');
  for (const p of square.slice(0, 3)) await clickAt(...p);
  { const [u, v] = await at(...square[3]); await mouse.dblclick(u, v); }
  await until('the obstacle to be added and selected', () => window.rilbedEditor.doc.obstacles?.length === 1 && window.rilbedEditor.selection?.type === 'obstacle');
  let d = await doc();
  check(d.obstacles[0].polygon.length === 4 && d.obstacles[0].polygon.every((p, i) => nearPoint(p, square[i])),
    `the obstacle is ${JSON.stringify(d.obstacles[0].polygon)}, not the square ${JSON.stringify(square)} clicked`);
  ok(`obstacle added by four clicks (the last a double-click): ${JSON.stringify(d.obstacles[0].polygon)}`);
  // ... and its third vertex dragged 2 cm right and 1 cm up.
  const moved = [ox + 0.07, oy + 0.06];
  await dragPx(await at(...square[2]), await at(...moved));
  await until('the obstacle\'s third vertex to move', ([x, y]) => {
    const p = window.rilbedEditor.doc.obstacles[0].polygon[2];
    return Math.abs(p[0] - x) < 0.004 && Math.abs(p[1] - y) < 0.004;
  }, moved);
  square[2] = moved;
  ok(`the obstacle's third vertex dragged to ${JSON.stringify(moved)}`);

  // 2b. A track: three clicks and Enter, 3 cm wide, open.
  const track = [[0.2, 0.12], [0.7, 0.2], [1.3, 0.12]];
  await page.check('input[name="editor-tool"][value="track"]');
  await page.fill('#editor-new-track-width', '0.03');
  for (const p of track) await clickAt(...p);
  await page.keyboard.press('Enter');
  await until('the track to be added', () => window.rilbedEditor.doc.tracks?.length === 1);
  d = await doc();
  check(d.tracks[0].points.length === 3 && d.tracks[0].points.every((p, i) => nearPoint(p, track[i])) && d.tracks[0].width_m === 0.03 &&
    d.tracks[0].closed === false, `the track is ${JSON.stringify(d.tracks[0])}, not ${JSON.stringify(track)} 0.03 m wide, open`);
  ok(`track added by three clicks and Enter: ${JSON.stringify(d.tracks[0])}`);

  // 2c. A beacon: id 5, aperture 120°, range 1.5 m, pressed and dragged up-right to face 45°.
  const beacon = freeSpot(0.08, 'the beacon');
  taken.push({ x: beacon[0], y: beacon[1], r: 0.03 });
  await page.check('input[name="editor-tool"][value="beacon"]');
  await page.fill('#editor-new-beacon-id', '5');
  await page.fill('#editor-new-beacon-aperture', '120');
  await page.fill('#editor-new-beacon-range', '1.5');
  {
    const [u, v] = await at(...beacon);
    await dragPx([u, v], [u + 40, v - 40]);
  }
  await until('the beacon to be added', () => window.rilbedEditor.doc.beacons?.length === 1);
  d = await doc();
  const b = d.beacons[0];
  check(b.id === 5 && nearPoint(b.position, beacon) && b.aperture_deg === 120 && b.range_m === 1.5 && angleOff(b.facing_deg, 45) <= TOLERANCE_DEG,
    `the beacon is ${JSON.stringify(b)}, not id 5 at ${JSON.stringify(beacon)}, aperture 120, range 1.5, facing 45`);
  ok(`beacon added by a press and a drag to aim it: ${JSON.stringify(b)}`);

  // 2d. A robot: one click, controller wander; it gets the next id, 9.
  const robot9 = freeSpot(0.09, 'robot 9');
  taken.push({ x: robot9[0], y: robot9[1], r: 0.03 });
  await page.check('input[name="editor-tool"][value="robot"]');
  await page.selectOption('#editor-new-controller', 'wander');
  await clickAt(...robot9);
  await until('robot 9 to be added', () => window.rilbedEditor.doc.robots.some((r) => r.id === 9));
  d = await doc();
  const r9 = d.robots.find((r) => r.id === 9);
  check(nearPoint(r9.pose, robot9) && r9.controller === 'wander' && r9.kind === undefined,
    `robot 9 is ${JSON.stringify(r9)}, not a virtual wanderer at ${JSON.stringify(robot9)}`);
  ok(`robot added by a click: ${JSON.stringify(r9)}`);

  // 2e. Robot 3 dragged to a free place (select tool), then turned by its handle to 135°.
  await page.check('input[name="editor-tool"][value="select"]');
  const r3 = d.robots.find((r) => r.id === 3);
  const to3 = freeSpot(0.09, 'robot 3');
  taken.push({ x: to3[0], y: to3[1], r: 0.03 });
  await dragPx(await at(r3.pose[0], r3.pose[1]), await at(...to3));
  await until('robot 3 to move', ([x, y]) => {
    const r = window.rilbedEditor.doc.robots.find((q) => q.id === 3);
    return Math.abs(r.pose[0] - x) < 0.004 && Math.abs(r.pose[1] - y) < 0.004;
  }, to3);
  d = await doc();
  check(d.robots.find((r) => r.id === 3).pose[2] === r3.pose[2], `dragging robot 3 turned it: ${JSON.stringify(d.robots.find((r) => r.id === 3))}`);
  ok(`robot 3 dragged from (${r3.pose[0]}, ${r3.pose[1]}) to ${JSON.stringify(to3)}, heading kept (${r3.pose[2]}°)`);
  const handle = await page.evaluate(() => window.rilbedEditor.rotateHandle());
  check(handle, 'robot 3 is selected but has no rotation handle');
  {
    const [cu, cv] = await at(...to3); // (and box, now)
    const a = (135 * Math.PI) / 180;
    await dragPx([box.x + handle[0], box.y + handle[1]], [cu + 50 * Math.cos(a), cv - 50 * Math.sin(a)]);
  }
  await until('robot 3 to turn to 135°', () => {
    const r = window.rilbedEditor.doc.robots.find((q) => q.id === 3);
    return Math.abs(((r.pose[2] - 135 + 540) % 360) - 180) <= 1.5;
  });
  d = await doc();
  const r3b = d.robots.find((r) => r.id === 3);
  check(nearPoint(r3b.pose, to3), `turning robot 3 moved it: ${JSON.stringify(r3b)}`);
  ok(`robot 3 turned by dragging its handle: pose ${JSON.stringify(r3b.pose)}`);

  // 2f. Robot 5 turned by shift + wheel: 5° a notch, wheel up turns left.
  const r5 = d.robots.find((r) => r.id === 5);
  {
    const [u, v] = await at(r5.pose[0], r5.pose[1]);
    await mouse.move(u, v);
    await page.keyboard.down('Shift');
    await mouse.wheel(0, -100);
    await page.keyboard.up('Shift');
  }
  const want5 = ((r5.pose[2] + 5 + 540) % 360) - 180;
  await until('robot 5 to turn by 5° on shift + wheel', (w) => {
    const r = window.rilbedEditor.doc.robots.find((q) => q.id === 5);
    return Math.abs(((r.pose[2] - w + 540) % 360) - 180) < 0.05;
  }, want5);
  ok(`robot 5 turned by shift + wheel from ${r5.pose[2]}° to ${want5.toFixed(1)}°`);

  // 2g. Robot 8 clicked and deleted with the Delete key.
  const r8 = d.robots.find((r) => r.id === 8);
  await clickAt(r8.pose[0], r8.pose[1]);
  await until('robot 8 to be selected', () => window.rilbedEditor.selection?.type === 'robot' && window.rilbedEditor.selection.id === 8);
  await page.keyboard.press('Delete');
  await until('robot 8 to be deleted', () => !window.rilbedEditor.doc.robots.some((r) => r.id === 8));
  ok('robot 8 clicked and deleted with the Delete key');

  // The editor, as a person sees it: the obstacle selected, its handles showing.
  await clickAt(ox - 0.03, oy - 0.03);
  await until('the obstacle to be selected', () => window.rilbedEditor.selection?.type === 'obstacle');
  const shot = path.join(state.artifacts, 'editor.png');
  await page.locator('#editor').screenshot({ path: shot });
  ok(`screenshot of the editor: ${shot}`);

  // 3. Save: the download, the text shown, what it holds, and rilbed run accepting it.
  const save = async (what, dir = state.tmp) => {
    const [download] = await Promise.all([
      page.waitForEvent('download', { timeout: DEADLINE_MS }).catch((e) => fail(`no download after Save (${what}): ${e.message.split('\n')[0]}`)),
      page.click('#editor-save'),
    ]);
    check(download.suggestedFilename() === 'scenario.yaml', `the download is named ${download.suggestedFilename()}, not scenario.yaml`);
    const file = path.join(dir, `saved-${what}.yaml`);
    await download.saveAs(file);
    const text = fs.readFileSync(file, 'utf8');
    const shown = await page.inputValue('#editor-yaml');
    check(text === shown, `the file saved (${what}) is not the text the page shows:\n${text}\n--- shown ---\n${shown}`);
    return { file, text };
  };
  const saved = await save('edited');
  const s = yaml.load(saved.text);
  check(s.obstacles?.length === 1 && s.obstacles[0].polygon.every((p, i) => nearPoint(p, square[i])),
    `saved obstacles ${JSON.stringify(s.obstacles)}, expected ${JSON.stringify(square)}`);
  check(s.tracks?.length === 1 && s.tracks[0].points.every((p, i) => nearPoint(p, track[i])) && s.tracks[0].width_m === 0.03,
    `saved tracks ${JSON.stringify(s.tracks)}, expected ${JSON.stringify(track)}`);
  check(s.beacons?.length === 1 && s.beacons[0].id === 5 && nearPoint(s.beacons[0].position, beacon) && s.beacons[0].aperture_deg === 120 &&
    s.beacons[0].range_m === 1.5 && angleOff(s.beacons[0].facing_deg, 45) <= TOLERANCE_DEG, `saved beacons ${JSON.stringify(s.beacons)}`);
  const ids = s.robots.map((r) => r.id).sort((a, b) => a - b);
  check(JSON.stringify(ids) === '[1,2,3,4,5,6,7,9]', `saved robots ${ids}, expected 1-7 and 9`);
  const s3 = s.robots.find((r) => r.id === 3), s5 = s.robots.find((r) => r.id === 5), s9 = s.robots.find((r) => r.id === 9);
  check(nearPoint(s3.pose, to3) && angleOff(s3.pose[2], 135) <= TOLERANCE_DEG, `saved robot 3 ${JSON.stringify(s3)}`);
  check(angleOff(s5.pose[2], want5) < 0.05 && nearPoint(s5.pose, r5.pose), `saved robot 5 ${JSON.stringify(s5)}`);
  check(nearPoint(s9.pose, robot9) && s9.controller === 'wander', `saved robot 9 ${JSON.stringify(s9)}`);
  ok(`the saved scenario.yaml (${saved.text.split('\n').length} lines) holds the obstacle, track, beacon and robot 9 where ` +
     'the mouse put them, robot 3 moved and turned, robot 5 turned, no robot 8');
  runAccepts(binary, saved.file, ['--fast', '--duration', '2'], path.join(state.tmp, 'run-edited'));
  ok('rilbed run SAVED --fast --duration 2 exits 0');

  // 4. Every shipped scenario, loaded and saved unchanged. Saved where a path relative to
  // the scenario (a Python controller's `../examples/python/...`) still leads to its file:
  // a scenarios/ folder beside a link to the project's examples/.
  const shippedDir = path.join(state.tmp, 'scenarios');
  fs.mkdirSync(shippedDir);
  fs.symlinkSync(path.resolve(SCENARIOS, '../examples'), path.join(state.tmp, 'examples'));
  const files = fs.readdirSync(SCENARIOS).filter((f) => f.endsWith('.yaml')).sort();
  check(files.length > 0, `no scenarios in ${SCENARIOS}`);
  for (const f of files) {
    const original = path.join(SCENARIOS, f);
    const loadsBefore = await page.evaluate(() => window.rilbedEditor.loads);
    await page.setInputFiles('#editor-file', original);
    await until(`the editor to load ${f}`, ([n, name]) => window.rilbedEditor.loads > n && window.rilbedEditor.loadedName === name, [loadsBefore, f]);
    const out = await save(path.basename(f, '.yaml'), shippedDir);
    const a = yaml.load(fs.readFileSync(original, 'utf8'));
    const c = yaml.load(out.text);
    try {
      assert.deepStrictEqual(c, a);
    } catch (e) {
      fail(`${f} loaded and saved is not the same scenario:\n${e.message.slice(0, 3000)}`);
    }
    const real = (a.robots || []).some((r) => r.kind === 'real');
    runAccepts(binary, out.file, ['--fast', '--duration', '1', ...(real ? ['--all-virtual'] : [])], path.join(state.tmp, `run-${f}`));
    ok(`${f}: loaded, saved unchanged (js-yaml: deep-equal), rilbed run accepts it${real ? ' (--all-virtual)' : ''}`);
  }

  // 4b. Robots of parts: model, body and wheels kept, drawn and hit by their bodies.
  await checkBodies(state, page, until, binary, save, yaml);

  // 5. A group split by dragging one of its robots from the tray: convoy_mixed's real
  // robots 4-5, robot 4 put at (0.3, 0.3) (an entry of its own, before 5's: ID order); robot
  // 8 of group 6-8 deleted with the button.
  {
    const loadsBefore = await page.evaluate(() => window.rilbedEditor.loads);
    await page.setInputFiles('#editor-file', path.join(SCENARIOS, 'convoy_mixed.yaml'));
    await until('the editor to load convoy_mixed.yaml again', (n) => window.rilbedEditor.loads > n, loadsBefore);
    const tray4 = await page.evaluate(() => window.rilbedEditor.trayPosition(4));
    check(tray4, 'robot 4 of convoy_mixed.yaml (ids 4-5, pose random) is not in the tray');
    // Loading a file may leave the page scrolled to the file's input (it did once in a CI
    // run at -j2, the canvas 1069 px down): back to the canvas, as a person would scroll.
    await canvas.evaluate((el) => el.scrollIntoView({ block: 'center' }));
    box = await canvasBox();
    await dragPx([box.x + tray4[0], box.y + tray4[1]], await at(0.3, 0.3));
    await until('robot 4 to leave its group with a pose', () => window.rilbedEditor.doc.robots.some((r) => r.id === 4 && Array.isArray(r.pose)));
    const tray8 = await page.evaluate(() => window.rilbedEditor.trayPosition(8));
    await mouse.click(box.x + tray8[0], box.y + tray8[1]);
    await until('robot 8 to be selected in the tray', () => window.rilbedEditor.selection?.id === 8);
    await page.click('#editor-delete');
    await until('robot 8 to be deleted', () => !window.rilbedEditor.trayPosition(8));
    const out = await save('split');
    const got = yaml.load(out.text).robots;
    const want = [
      { ids: '1-3', pose: 'random', controller: 'convoy', noise: { slip_sd: 0.02 } },
      { id: 4, kind: 'real', link: { emulate: true }, pose: [0.3, 0.3, 90], controller: 'convoy' },
      { id: 5, kind: 'real', link: { emulate: true }, pose: 'random', controller: 'convoy' },
      { ids: '6-7', pose: 'random', controller: 'convoy', noise: { slip_sd: 0.02 } },
    ];
    check(got.length === 4 && nearPoint(got[1].pose, [0.3, 0.3]), `the split robots are ${JSON.stringify(got)}`);
    got[1].pose = [0.3, 0.3, got[1].pose[2]];
    try {
      assert.deepStrictEqual(got, want);
    } catch {
      fail(`convoy_mixed.yaml with robot 4 placed and 8 deleted: robots ${JSON.stringify(got)}, expected ${JSON.stringify(want)}`);
    }
    runAccepts(binary, out.file, ['--fast', '--duration', '1', '--all-virtual'], path.join(state.tmp, 'run-split'));
    ok(`robot 4 dragged from the tray splits ids 4-5 (its link kept), robot 8 deleted by the button leaves ids 6-7; rilbed run accepts it: ${JSON.stringify(got)}`);
  }

  // 6. "Poses from run" on convoy_sim.yaml: every robot its own entry at the run's pose,
  // its kind, noise and sensors kept.
  {
    const loadsBefore = await page.evaluate(() => window.rilbedEditor.loads);
    await page.setInputFiles('#editor-file', path.join(SCENARIOS, 'convoy_sim.yaml'));
    await until('the editor to load convoy_sim.yaml again', (n) => window.rilbedEditor.loads > n, loadsBefore);
    await page.click('#editor-poses-from-run');
    await until('every robot to have a pose', () => window.rilbedEditor.doc.robots.length === 8 && window.rilbedEditor.doc.robots.every((r) => Array.isArray(r.pose)));
    const out = await save('poses');
    const original = yaml.load(fs.readFileSync(path.join(SCENARIOS, 'convoy_sim.yaml'), 'utf8')).robots[0];
    const { ids: _ids, pose: _pose, ...rest } = original;
    const got = yaml.load(out.text).robots;
    got.forEach((r, k) => {
      const { id, pose, ...others } = r;
      check(id === k + 1 && Array.isArray(pose) && pose.length === 3, `robot entry ${k}: ${JSON.stringify(r)}`);
      try {
        assert.deepStrictEqual(others, rest);
      } catch {
        fail(`robot ${id} after "Poses from run" is ${JSON.stringify(r)}: its other keys are not ${JSON.stringify(rest)}`);
      }
    });
    runAccepts(binary, out.file, ['--fast', '--duration', '1'], path.join(state.tmp, 'run-poses'));
    ok(`"Poses from run" on convoy_sim.yaml: robots 1-8 each at the run's pose, kind, noise and sensors kept; rilbed run accepts it`);
  }

  // 7. The controllers: the registry's, in the lists, the forms and the checks.
  const registry = cliRegistry(binary);
  await checkControllerLists(page, until, registry);
  await checkParameterForm(state, page, until, registry);
  await checkRegistryFailure(state, context, url);

  check(state.pageErrors.length === 0, `the page logged errors:\n${state.pageErrors.join('\n')}`);
  ok('the page logged no console error and threw nothing');
}

// ---------------------------------------------------------------- the controller registry
// What `RILBED controllers --json` prints: the registry the server serves at controllers.json.
function cliRegistry(binary) {
  const r = spawnSync(binary, ['controllers', '--json'], { encoding: 'utf8', timeout: 60000 });
  check(r.status === 0, `rilbed controllers --json ended with ${r.error ? r.error.message : r.signal || `exit code ${r.status}`}: ${r.stderr}`);
  const list = JSON.parse(r.stdout);
  check(Array.isArray(list) && list.length > 0, `rilbed controllers --json printed no list: ${r.stdout.slice(0, 300)}`);
  return list;
}

const optionValues = (page, selector) => page.$$eval(`${selector} option`, (os) => os.map((o) => o.value));

// The page's controllers.json is the command's registry, and the editor's choices (the new
// robot's and a robot's form) are exactly its names, in its order.
async function checkControllerLists(page, until, registry) {
  const names = registry.map((c) => c.name);
  const served = await page.evaluate(() => fetch('controllers.json').then((r) => r.json()));
  try {
    assert.deepStrictEqual(served, registry);
  } catch (e) {
    fail(`the page's controllers.json is not what rilbed controllers --json prints:\n${e.message.slice(0, 2000)}`);
  }
  const editor = await until('the editor to have the list of controllers', () => window.rilbedEditor.controllers.loaded && window.rilbedEditor.controllers);
  check(editor.error === null, `the editor says the list of controllers did not load: ${editor.error}`);
  check(await page.isHidden('#editor-controllers'), 'the editor still shows a note about the list of controllers although it loaded');
  const newRobot = await optionValues(page, '#editor-new-controller');
  check(JSON.stringify(newRobot) === JSON.stringify(names), `the new robot's controllers are ${newRobot}, not the registry's ${names}`);
  await loadScenario(page, until, 'wander.yaml');
  await selectTrayRobot(page, until, 1);
  const form = await optionValues(page, '#editor-form select[name=controller]');
  check(JSON.stringify(form) === JSON.stringify(names), `robot 1's controller choices are ${form}, not the registry's ${names}`);
  check(await page.inputValue('#editor-form select[name=controller]') === 'wander', 'robot 1 of wander.yaml does not show controller wander');
  ok(`controllers.json is rilbed controllers --json; the editor offers exactly its controllers (${names.join(', ')}) for a new robot and in a robot's form`);
}

// A scenario whose robots name models (robots/*.yaml) and override their bodies and
// wheels; robot 4's outline in block style (saved in flow style, the same scenario).
const BODIES_YAML = `# editor_test.js: robots of parts.
name: bodies
field: {width_m: 1.2, height_m: 0.8}
duration_s: 30
robots:
  - ids: 1-2
    model: epuck
    pose: random
    controller: wander
  - id: 3
    model: robots/square.yaml
    pose: [0.3, 0.4, 30]
    controller: wander
    wheels: {base_m: 0.058}
  - id: 4
    model: epuck
    body:
      outline_m:
        - [0.065, 0]
        - [-0.025, 0.035]
        - [-0.025, -0.035]
    wheels: {base_m: 0.05, radius_m: 0.012}
    pose: [0.6, 0.4, 90]
    controller: wander
  - id: 5
    body: {radius_m: 0.05}
    pose: [0.9, 0.4, 0]
    controller: wander
`;

// 4b. BODIES_YAML loaded and saved: the same scenario (model, body and wheels kept), no
// problem found, rilbed run accepts it; robot 5's 50 mm disc and robot 4's wedge drawn
// (red on their edges: on the disc's, none on a Khepera's within it; on the wedge's back
// corners, 15 mm beyond a Khepera's edge), robot 5 selected by a click 45 mm
// from its centre (outside a Khepera's 27.5 mm); robot 3 (a model alone) labelled with it.
async function checkBodies(state, page, until, binary, save, yaml) {
  const file = path.join(state.tmp, 'bodies.yaml');
  fs.writeFileSync(file, BODIES_YAML);
  const loadsBefore = await page.evaluate(() => window.rilbedEditor.loads);
  await page.setInputFiles('#editor-file', file);
  await until('the editor to load bodies.yaml', ([n, name]) => window.rilbedEditor.loads > n && window.rilbedEditor.loadedName === name, [loadsBefore, 'bodies.yaml']);
  const out = await save('bodies');
  try {
    assert.deepStrictEqual(yaml.load(out.text), yaml.load(BODIES_YAML));
  } catch (e) {
    fail(`bodies.yaml loaded and saved is not the same scenario:\n${e.message.slice(0, 3000)}`);
  }
  check(/^ {4}body: \{outline_m: \[\[0\.065, 0\], \[-0\.025, 0\.035\], \[-0\.025, -0\.035\]\]\}$/m.test(out.text),
    `the saved bodies.yaml does not hold robot 4's outline in flow style:\n${out.text}`);
  const problems = await page.evaluate(() => window.rilbedEditor.problems());
  check(problems.length === 0, `the editor finds problems in bodies.yaml: ${problems.join(' ')}`);
  runAccepts(binary, out.file, ['--fast', '--duration', '1'], path.join(state.tmp, 'run-bodies'));
  ok('bodies.yaml (model:, body: as a disc and as an outline, wheels:): loaded, saved unchanged, no problem, rilbed run accepts it');

  const canvas = page.locator('#editor-canvas');
  await canvas.evaluate((el) => el.scrollIntoView({ block: 'center' }));
  await page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve))));
  // Red (#d22828) within 1.5 px of robot-frame points of robot (x, y, heading th degrees).
  const red = await page.evaluate(() => {
    const E = window.rilbedEditor, c = document.getElementById('editor-canvas');
    const dpr = window.devicePixelRatio || 1, img = c.getContext('2d').getImageData(0, 0, c.width, c.height);
    const near = ([x, y]) => {
      const [u, v] = E.project(x, y);
      let n = 0;
      for (let py = Math.floor((v - 1.5) * dpr); py <= Math.ceil((v + 1.5) * dpr); ++py) {
        for (let px = Math.floor((u - 1.5) * dpr); px <= Math.ceil((u + 1.5) * dpr); ++px) {
          const i = 4 * (py * img.width + px);
          if (Math.abs(img.data[i] - 0xd2) < 40 && Math.abs(img.data[i + 1] - 0x28) < 40 && Math.abs(img.data[i + 2] - 0x28) < 40 && img.data[i + 3] > 200) ++n;
        }
      }
      return n;
    };
    const at = (x, y, th) => ([fx, fy]) => {
      const a = (th * Math.PI) / 180;
      return [x + Math.cos(a) * fx - Math.sin(a) * fy, y + Math.sin(a) * fx + Math.cos(a) * fy];
    };
    const disc = (r) => [90, 180, 270].map((d) => [r * Math.cos((d * Math.PI) / 180), r * Math.sin((d * Math.PI) / 180)]);
    return {
      r5: disc(0.05).map(at(0.9, 0.4, 0)).map(near), r5khepera: disc(0.0275).map(at(0.9, 0.4, 0)).map(near),
      // Its back corners, 43 mm from its centre (15 mm beyond a Khepera's edge), and its back's middle.
      r4: [[-0.025, 0.035], [-0.025, 0], [-0.025, -0.035]].map(at(0.6, 0.4, 90)).map(near),
    };
  });
  check(red.r5.every((n) => n > 0) && red.r5khepera.every((n) => n === 0),
    `robot 5 (body: {radius_m: 0.05}) is not drawn as a 50 mm disc: red at its edge ${red.r5}, at a Khepera's ${red.r5khepera}`);
  check(red.r4.every((n) => n > 0), `robot 4 (its outline) is not drawn as its wedge: red at its back corners and middle ${red.r4}`);
  const box = await canvas.boundingBox();
  const [u, v] = await page.evaluate(() => window.rilbedEditor.project(0.9, 0.445));
  await page.mouse.click(box.x + u, box.y + v);
  await until('robot 5 to be selected by a click 45 mm from its centre', () => window.rilbedEditor.selection?.type === 'robot' && window.rilbedEditor.selection.id === 5);
  const shot = path.join(state.artifacts, 'editor-bodies.png');
  await page.locator('#editor').screenshot({ path: shot });
  ok(`the editor draws robot 5's 50 mm disc (red on its edge, none on a Khepera's) and robot 4's wedge (red at its back corners), and a click 45 mm ` +
     `from robot 5's centre selects it (screenshot ${shot})`);
}

async function loadScenario(page, until, name) {
  const loadsBefore = await page.evaluate(() => window.rilbedEditor.loads);
  await page.setInputFiles('#editor-file', path.join(SCENARIOS, name));
  await until(`the editor to load ${name}`, ([n, f]) => window.rilbedEditor.loads > n && window.rilbedEditor.loadedName === f, [loadsBefore, name]);
}

// Clicks robot `id` in the tray (a robot with a random pose) and waits for it to be selected.
async function selectTrayRobot(page, until, id) {
  const canvas = page.locator('#editor-canvas');
  await canvas.evaluate((el) => el.scrollIntoView({ block: 'center' }));
  const at = await page.evaluate((k) => window.rilbedEditor.trayPosition(k), id);
  check(at, `robot ${id} is not in the tray`);
  const b = await canvas.boundingBox();
  await page.mouse.click(b.x + at[0], b.y + at[1]);
  await until(`robot ${id} to be selected`, (k) => window.rilbedEditor.selection?.id === k, id);
}

const problemsShown = (page) => page.$$eval('#editor-problems li', (lis) => lis.map((li) => li.textContent));

// Types `value` into parameter `name`'s input of the form, as a person does (then Tab).
async function typeParam(page, name, value) {
  const input = page.locator(`#editor-form input[name=param_${name}]`);
  await input.fill(String(value));
  await input.press('Tab');
}

// Robot 1 of wander.yaml (selected): a number input per parameter of wander with its unit,
// default, range and summary from the registry; a speed out of range flagged, one in range
// saved in params, an emptied one gone; another controller keeps the params it takes, adds
// a sensor it requires and asks for its required params; `none` drops them all.
async function checkParameterForm(state, page, until, registry) {
  const wander = registry.find((c) => c.name === 'wander');
  const speed = wander && wander.params.find((p) => p.name === 'speed_mps');
  check(speed, 'the registry has no wander with a speed_mps parameter');
  const shown = await page.$$eval('#editor-form input[name^=param_]', (inputs) => inputs.map((i) => ({
    name: i.name, placeholder: i.placeholder, min: i.min, max: i.max, title: i.closest('label').title,
    unit: i.closest('label').querySelector('.editor-unit')?.textContent,
  })));
  check(JSON.stringify(shown.map((i) => i.name)) === JSON.stringify(wander.params.map((p) => `param_${p.name}`)),
    `robot 1's parameter inputs are ${shown.map((i) => i.name)}, not wander's ${wander.params.map((p) => p.name)}`);
  const s = shown[0];
  check(s.unit === speed.unit && s.placeholder === String(speed.default) && s.min === String(speed.min) && s.max === String(speed.max) &&
    s.title.includes(speed.summary), `the speed_mps input shows ${JSON.stringify(s)}, not the registry's ${JSON.stringify(speed)}`);
  ok(`robot 1 (wander): a speed_mps input in ${s.unit}, placeholder ${s.placeholder}, min ${s.min}, max ${s.max}, "${speed.summary}" on hover`);
  const shot = path.join(state.artifacts, 'editor-params.png');
  await page.locator('#editor').screenshot({ path: shot });
  ok(`screenshot of a robot's parameters: ${shot}`);

  const tooFast = speed.max + 4;
  const flagged = `robots[0]: params.speed_mps must be ${speed.min} to ${speed.max} (${speed.unit}), not ${tooFast}.`;
  await typeParam(page, 'speed_mps', tooFast);
  await until(`the problems to flag speed_mps ${tooFast}`, (text) => window.rilbedEditor.problems().includes(text), flagged);
  check((await problemsShown(page)).includes(flagged), `the page's problems do not show "${flagged}": ${await problemsShown(page)}`);
  await typeParam(page, 'speed_mps', 0.08);
  await until('speed_mps 0.08 to be saved in params and its problem to go', (text) => {
    const e = window.rilbedEditor.doc.robots[0];
    return e.params?.speed_mps === 0.08 && !window.rilbedEditor.problems().includes(text);
  }, flagged);
  check(/params: \{speed_mps: 0\.08\}/.test(await page.inputValue('#editor-yaml')), 'the YAML shown does not hold params: {speed_mps: 0.08}');
  ok(`speed_mps ${tooFast} flagged as "${flagged}"; 0.08 accepted and saved as params: {speed_mps: 0.08}`);

  await checkControllerChange(page, until, registry);
  await typeParam(page, 'speed_mps', '');
  await until('an emptied speed_mps to leave params', () => window.rilbedEditor.doc.robots[0].params === undefined);
  ok('speed_mps emptied: robot 1\'s params are gone (the default applies)');
}

const setRobotController = (page, name) => page.selectOption('#editor-form select[name=controller]', name);

async function checkControllerChange(page, until, registry) {
  const takes = (name, param) => registry.find((c) => c.name === name)?.params.some((p) => p.name === param);
  check(takes('track_follow', 'speed_mps') && takes('goto', 'speed_mps'), 'the registry\'s track_follow or goto takes no speed_mps');
  await setRobotController(page, 'track_follow');
  await until('track_follow to keep speed_mps and get track sensors', () => {
    const e = window.rilbedEditor.doc.robots[0];
    return e.controller === 'track_follow' && e.params?.speed_mps === 0.08 && Array.isArray(e.sensors?.track) && e.sensors.track.length > 0;
  });
  const goto = registry.find((c) => c.name === 'goto');
  const required = goto.params.filter((p) => p.required).map((p) => `robots[0]: controller goto needs parameter '${p.name}' (${p.summary}).`);
  check(required.length > 0, 'the registry\'s goto requires no parameter');
  await setRobotController(page, 'goto');
  await until('goto\'s required parameters to be asked for', (want) => want.every((t) => window.rilbedEditor.problems().includes(t)), required);
  await setRobotController(page, 'none');
  await until('none to drop every parameter', () => window.rilbedEditor.doc.robots[0].controller === 'none' && window.rilbedEditor.doc.robots[0].params === undefined);
  check(await page.$$eval('#editor-form input[name^=param_]', (inputs) => inputs.length) === 0, 'robot 1 with controller none still shows parameter inputs');
  await setRobotController(page, 'wander');
  await typeParam(page, 'speed_mps', 0.08);
  await until('wander with speed_mps 0.08 again', () => window.rilbedEditor.doc.robots[0].params?.speed_mps === 0.08);
  ok(`controller changes: track_follow keeps speed_mps and gets track sensors; goto asks for ${goto.params.filter((p) => p.required).map((p) => p.name)}; none drops every parameter`);
}

// A page whose controllers.json fails: the editor says so, in red, and offers no
// controller (no list of its own to fall back on).
async function checkRegistryFailure(state, context, url) {
  const page = await context.newPage();
  await page.route('**/controllers.json*', (route) => route.fulfill({ status: 503, contentType: 'text/plain', body: 'unavailable\n' }));
  await page.goto(url);
  await page.waitForFunction(() => window.rilbedEditor?.controllers.loaded, null, { timeout: DEADLINE_MS, polling: 50 })
    .catch((e) => fail(`the editor did not finish asking for controllers.json (${e.message.split('\n')[0]})`));
  if (!(await page.evaluate(() => document.getElementById('editor-panel').open))) await page.click('#editor-panel > summary');
  const seen = await page.evaluate(() => ({
    editor: window.rilbedEditor.controllers, note: document.getElementById('editor-controllers').textContent,
    visible: !document.getElementById('editor-controllers').hidden, colour: getComputedStyle(document.getElementById('editor-controllers')).color,
    options: document.querySelectorAll('#editor-new-controller option').length, problems: window.rilbedEditor.problems(),
  }));
  check(seen.visible && /did not load/.test(seen.note) && /503/.test(seen.note) && seen.editor.error,
    `with controllers.json failing the editor says ${JSON.stringify(seen.note)} (shown: ${seen.visible})`);
  check(seen.options === 0 && seen.editor.names.length === 0, `with controllers.json failing the editor still offers ${seen.options} controllers`);
  check(seen.problems.some((p) => /not checked/.test(p)), `with controllers.json failing the problems do not say the controllers go unchecked: ${seen.problems}`);
  await page.locator('#editor-controllers').scrollIntoViewIfNeeded();
  const shot = path.join(state.artifacts, 'editor-no-registry.png');
  await page.locator('#editor').screenshot({ path: shot });
  await page.close();
  ok(`controllers.json answering 503: the editor says "${seen.note}" and offers no controller (screenshot ${shot})`);
}

run(main, {
  name: 'editor_test',
  summary: (passed, failed, seconds) => (failed ? null : `editor_test: PASS (${passed} checks, ${seconds} s)`),
});
