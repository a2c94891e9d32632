#!/usr/bin/env node
// The web panel's vision settings (threshold, contrast, marker size limits,
// brightness, their effect visible live) in a real browser: Debian's Chromium, driven by
// playwright-core, against `rilbed run --gui` with emulated real robots and its emulated
// overhead camera. The settings are the run's Foxglove parameters (vision.brightness,
// vision.contrast, vision.threshold, vision.min_diameter_px, vision.max_diameter_px,
// vision.min_score).
//
//   node web/tests/vision_test.js RILBED MIXED_SCENARIO SIM_SCENARIO [ARTEFACT_DIR]
//
// MIXED_SCENARIO is scenarios/convoy_mixed.yaml: the test writes a copy of it whose robots
// all stand still (4 and 5 real, at known poses in the camera's view; 1-3 and 6-8
// virtual), so that the camera image changes only by the settings, and runs `RILBED run
// COPY --realtime --duration 300 --gui --gui-port 0 --out TMPDIR`. It checks:
//   1. the page's Vision section: a slider and a readout per setting, its unit in the
//      label and a tooltip, the run's defaults shown, as is the YAML snippet for the
//      scenario's camera: key; both real robots' markers detected;
//   2. brightness, dragged with the mouse: the page sends a few requests a second, not
//      one per mouse move, the last of them the slider's final value, which the run
//      echoes and the readout shows; the camera layer of the live view (every other
//      overlay off) gets darker by about as much;
//   3. contrast 0.4: the camera layer's spread of grey levels shrinks, its mean moves
//      toward mid-grey;
//   4. min score 1: the real robots' detections vanish from the page; "defaults"
//      brings every setting back (one request) and the detections with them;
//   5. refusals: threshold 1000 and a min diameter above the max, asked through
//      window.rilbed.vision.set, are refused: the values stay, the page says why (in the
//      Vision section and as the console's other refusals);
//   6. a second page sees the first page's change (subscribeParameterUpdates);
//   7. SIM_SCENARIO (scenarios/convoy_sim.yaml, no camera): the Vision section greyed,
//      its controls disabled, a one-line reason;
// and that no page logged a console error or threw. Screenshots go to $RILBED_ARTIFACTS,
// else ARTEFACT_DIR (CTest passes BUILD/web-artifacts), else a temp folder; their paths
// are printed. Every wait polls with a deadline; on any failure it says what it was
// waiting for, shows the end of rilbed's output, kills rilbed and the browser and exits 1.
'use strict';

const fs = require('node:fs');
const path = require('node:path');
const {
  ok, check, sleep, poll, startRilbed, commandLine, checkBinary, checkScenario, tempFolder,
  withRobots, requirePlaywright, launchBrowser, newContext, openPage, useArtefacts, screenshot, run,
} = require('./support');

const WATCHDOG_MS = 280000;      // the whole test (CTest's TIMEOUT is 300 s)
const DEFAULTS = { brightness: 0, contrast: 1, threshold: 24, min_diameter_px: 18, max_diameter_px: 480, min_score: 0.75 };
const DEFAULT_YAML = 'vision: {brightness: 0, contrast: 1, threshold: 24, min_diameter_px: 18, max_diameter_px: 480, min_score: 0.75}';
const UNITS = { brightness: /grey levels/, contrast: /gain/, threshold: /grey levels/, min_diameter_px: /px/, max_diameter_px: /px/, min_score: /0.1/ };
const REAL = [4, 5];
const REAL_POSES = { 4: [0.45, 0.6, 0], 5: [1.05, 0.6, 90] }; // x_m, y_m, theta_deg: well inside the field
const MAX_REQUESTS_PER_S = 5;    // the page sends at most 4 a second (one each 250 ms), and one at the release

// ---------------------------------------------------------------- the scenario
// The mixed scenario's copy: its field, timing, camera and safety as shipped; every robot
// standing still, the real ones at known poses.
function mixedScenarioCopy(text) {
  const real = REAL.map((id) => `  - id: ${id}
    kind: real
    link: {emulate: true}
    pose: [${REAL_POSES[id].join(', ')}]
    controller: none`).join('\n');
  const robots = `robots:
  - ids: 1-3
    pose: random
    controller: none
${real}
  - ids: 6-8
    pose: random
    controller: none`;
  return withRobots(text, robots);
}

// ---------------------------------------------------------------- the page
// A page on `url` (support.js's openPage) whose setParameters requests (WebSocket frames it
// sends) are collected in state.sent[label] as {at, parameters}.
const openVisionPage = (state, context, label, url) => openPage(state, context, label, url, (page) => {
  state.sent[label] = [];
  page.on('websocket', (ws) => ws.on('framesent', (f) => {
    if (typeof f.payload !== 'string' || !f.payload.includes('"setParameters"')) return;
    const m = JSON.parse(f.payload);
    if (m.op === 'setParameters') state.sent[label].push({ at: Date.now(), parameters: m.parameters });
  }));
});

// What the page's Vision section shows.
function visionShown(page) {
  return page.evaluate(() => {
    const section = document.getElementById('vision');
    const rows = [...section.querySelectorAll('[data-param]')].map((row) => ({
      name: row.dataset.param, label: row.querySelector('span').textContent, tip: row.title,
      slider: row.querySelector('input').value, disabled: row.querySelector('input').disabled,
      readout: row.querySelector('output').textContent,
    }));
    return {
      rows, values: window.rilbed.vision.values, available: window.rilbed.vision.available,
      reason: document.getElementById('vision-reason').hidden ? null : document.getElementById('vision-reason').textContent,
      greyed: section.classList.contains('unavailable'), defaultsDisabled: document.getElementById('vision-defaults').disabled,
      yaml: document.getElementById('vision-yaml').textContent, found: document.getElementById('vision-found').textContent,
      reply: document.getElementById('vision-reply').textContent, replyColour: getComputedStyle(document.getElementById('vision-reply')).color,
      consoleReply: document.getElementById('reply').textContent,
    };
  });
}
const valueOf = (shown, key) => shown.values[`vision.${key}`];
const readoutOf = (shown, key) => shown.rows.find((r) => r.name === `vision.${key}`).readout;

// Waits until the run's value of every key of `want` (as the page holds it) is that.
function waitValues(page, want, what) {
  let last = null;
  return poll(`the run to echo ${what} (${JSON.stringify(want)})`, async () => {
    last = await visionShown(page);
    return Object.entries(want).every(([k, v]) => Math.abs(valueOf(last, k) - v) <= 1e-6 * Math.max(1, Math.abs(v))) && last;
  }, { describe: () => JSON.stringify(last && last.values) });
}

// The newest detections message the page holds: {frame, ids}.
const detectionsOf = (page) => page.evaluate(() => {
  const d = window.rilbed.run.detections;
  return d && { frame: d.frame, ids: d.detections.map((x) => x.id).sort((a, b) => a - b) };
});
// Waits until `n` detections messages in a row (fresh frames) have exactly `ids`.
async function waitDetections(page, ids, what, n = 5) {
  let streak = 0, lastFrame = -1, last = null;
  return poll(`${what}: ${n} frames in a row with the markers [${ids.join(', ')}]`, async () => {
    last = await detectionsOf(page);
    if (!last || last.frame === lastFrame) return false;
    lastFrame = last.frame;
    streak = last.ids.join() === ids.join() ? streak + 1 : 0;
    return streak >= n && last;
  }, { everyMs: 20, describe: () => JSON.stringify(last) });
}

// The camera layer of the live view (the caller has turned every other overlay off): the
// mean and the standard deviation of the grey level (0..255) over the middle of the camera
// image as drawn, once a camera frame newer than the last call has been drawn.
function cameraStats(page) {
  return page.evaluate(async () => {
    const R = window.rilbed;
    const seen = R.__visionTestImage;
    const end = performance.now() + 5000;
    while (R.run.image === seen && performance.now() < end) await new Promise((r) => setTimeout(r, 20));
    if (R.run.image === seen) return null;
    R.__visionTestImage = R.run.image;
    await new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
    const canvas = document.getElementById('view');
    const dpr = window.devicePixelRatio || 1;
    const cal = R.run.calibration;
    // The camera image is fitted to the canvas (the view not zoomed or panned).
    const w = canvas.clientWidth, h = canvas.clientHeight;
    const s = Math.min(w / cal.width_px, h / cal.height_px);
    const ox = (w - s * cal.width_px) / 2, oy = (h - s * cal.height_px) / 2;
    const x0 = Math.round((ox + 0.1 * s * cal.width_px) * dpr), y0 = Math.round((oy + 0.1 * s * cal.height_px) * dpr);
    const x1 = Math.round((ox + 0.9 * s * cal.width_px) * dpr), y1 = Math.round((oy + 0.9 * s * cal.height_px) * dpr);
    const d = canvas.getContext('2d').getImageData(x0, y0, x1 - x0, y1 - y0).data;
    let n = 0, sum = 0, sum2 = 0;
    for (let i = 0; i < d.length; i += 4) {
      const g = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
      n++; sum += g; sum2 += g * g;
    }
    const mean = sum / n;
    return { mean, sd: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), pixels: n, rect: [x0, y0, x1, y1] };
  });
}
// The camera stats once they satisfy `test` (new frames come after the run has the setting).
async function waitCamera(page, what, test) {
  let last = null;
  return poll(`the camera layer ${what}`, async () => {
    last = await cameraStats(page);
    return last && test(last) && last;
  }, { describe: () => JSON.stringify(last) });
}
const fmtStats = (s) => `mean ${s.mean.toFixed(1)}, sd ${s.sd.toFixed(1)}`;

// ---------------------------------------------------------------- the test
async function main(state) {
  const [binary, mixedScenario, simScenario, artefactArg] = commandLine('RILBED MIXED_SCENARIO SIM_SCENARIO [ARTEFACT_DIR]');
  const playwright = requirePlaywright();
  checkBinary(binary);
  checkScenario(mixedScenario);
  checkScenario(simScenario);

  state.sent = {};
  tempFolder(state, 'vision');
  useArtefacts(state, artefactArg, 'vision');

  const scenario = path.join(state.tmp, 'convoy_mixed_still.yaml');
  fs.writeFileSync(scenario, mixedScenarioCopy(fs.readFileSync(mixedScenario, 'utf8')));
  console.log(`# ${scenario}: ${mixedScenario} with every robot standing, ${REAL.join(' and ')} real at ` +
    REAL.map((id) => `(${REAL_POSES[id].join(', ')})`).join(' and '));
  const mixed = await startRilbed(state, binary, scenario, { label: 'mixed' });

  await launchBrowser(state, playwright);
  const context = await newContext(state, { viewport: { width: 1280, height: 1000 } });

  // ------------------------------------------------ 1. the Vision section, the defaults
  const page = await openVisionPage(state, context, 'page 1', mixed.url);
  const shown = await waitValues(page, DEFAULTS, 'the defaults');
  check(shown.available && !shown.greyed && shown.reason === null && !shown.defaultsDisabled,
    `the Vision section of a run with a camera: available ${shown.available}, greyed ${shown.greyed}, reason "${shown.reason}", defaults button disabled ${shown.defaultsDisabled}`);
  check(shown.rows.map((r) => r.name).join() === Object.keys(DEFAULTS).map((k) => `vision.${k}`).join(),
    `the Vision section's controls are ${shown.rows.map((r) => r.name).join(', ')}`);
  for (const r of shown.rows) {
    const key = r.name.slice('vision.'.length);
    check(UNITS[key].test(r.label), `${r.name}'s label "${r.label}" does not give its unit (${UNITS[key]})`);
    check(r.tip.length > 60 && /Raising it/.test(r.tip), `${r.name}'s tooltip "${r.tip}" does not say what it does and what raising it costs`);
    check(!r.disabled, `${r.name}'s slider is disabled`);
    check(Number(r.readout) === DEFAULTS[key], `${r.name}'s readout shows "${r.readout}", not ${DEFAULTS[key]}`);
  }
  check(shown.yaml === DEFAULT_YAML, `the YAML snippet is "${shown.yaml}", not "${DEFAULT_YAML}"`);
  const seen = await waitDetections(page, REAL, 'the real robots\' markers detected at the defaults');
  const found = await poll('the Vision section to say that both markers are found', async () => {
    const f = (await visionShown(page)).found;
    return /^found 2 \(ID 4, 5\)/.test(f) && f;
  });
  await screenshot(state, page, '01-defaults');
  ok(`the Vision section: ${shown.rows.map((r) => `"${r.label}" ${r.readout}`).join(', ')}, each with a tooltip; ` +
     `YAML "${shown.yaml}"; frame ${seen.frame}: markers ${seen.ids.join(', ')} ("${found}")`);

  // Only the camera layer on the canvas from here on.
  await page.evaluate(() => {
    for (const box of document.querySelectorAll('[data-overlay]')) {
      const want = box.dataset.overlay === 'camera';
      if (box.checked !== want) { box.checked = want; box.dispatchEvent(new Event('change')); }
    }
  });
  await poll('the page to draw the camera image (calibration and a frame received)', () => page.evaluate(() =>
    !!(window.rilbed.run.image && window.rilbed.run.calibration)));
  const base = await waitCamera(page, 'at the defaults', () => true);

  // ------------------------------------------------ 2. brightness, dragged with the mouse
  const slider = page.locator('#vision-brightness');
  const box = await slider.boundingBox();
  const y = box.y + box.height / 2;
  const sentBefore = state.sent['page 1'].length;
  await page.mouse.move(box.x + box.width / 2, y);  // the thumb, at 0 (mid-track)
  await page.mouse.down();
  const dragStart = Date.now();
  const STEPS = 40;
  for (let i = 1; i <= STEPS; i++) {
    await page.mouse.move(box.x + box.width * (0.5 - 0.25 * (i / STEPS)), y);  // to a quarter of the track: about -64
    await sleep(1500 / STEPS);
  }
  await page.mouse.up();
  const dragSeconds = (Date.now() - dragStart) / 1000;
  const final = Number(await slider.inputValue());
  check(final <= -40 && final >= -90, `the brightness slider ended at ${final} after dragging it to a quarter of its track`);
  const afterDrag = await waitValues(page, { brightness: final }, `brightness ${final}, the slider's final value`);
  await sleep(600);  // anything still throttled would have gone by now
  const requests = state.sent['page 1'].slice(sentBefore);
  const brightnessSent = requests.map((r) => r.parameters.find((p) => p.name === 'vision.brightness')).filter((p) => p);
  check(brightnessSent.length >= 2, `dragging brightness for ${dragSeconds.toFixed(1)} s sent ${brightnessSent.length} requests: it should send while moving`);
  check(requests.length <= MAX_REQUESTS_PER_S * dragSeconds + 2,
    `dragging brightness for ${dragSeconds.toFixed(1)} s (${STEPS} mouse moves) sent ${requests.length} requests, more than ${MAX_REQUESTS_PER_S} a second`);
  check(brightnessSent[brightnessSent.length - 1].value === final,
    `the last brightness sent was ${brightnessSent[brightnessSent.length - 1].value}, not the slider's final ${final}`);
  check(readoutOf(afterDrag, 'brightness') === String(final), `the brightness readout shows "${readoutOf(afterDrag, 'brightness')}", not ${final}`);
  check(afterDrag.yaml.includes(`brightness: ${final},`), `the YAML snippet "${afterDrag.yaml}" does not have brightness ${final}`);
  const dark = await waitCamera(page, `about ${-final} grey levels darker than at the defaults (${fmtStats(base)})`,
    (s) => s.mean < base.mean + 0.5 * final);
  await screenshot(state, page, '02-brightness');
  ok(`brightness dragged for ${dragSeconds.toFixed(1)} s (${STEPS} mouse moves): ${requests.length} requests ` +
     `(${brightnessSent.map((p) => p.value).join(', ')}), the run echoed ${final}, the readout shows it; the camera layer ` +
     `went from ${fmtStats(base)} to ${fmtStats(dark)}`);

  // ------------------------------------------------ 3. contrast
  await page.click('#vision-defaults');
  await waitValues(page, DEFAULTS, 'the defaults after "defaults"');
  const base2 = await waitCamera(page, `back to about its mean at the defaults (${fmtStats(base)})`,
    (s) => Math.abs(s.mean - base.mean) < 8);
  await page.locator('#vision-contrast').fill(String(Math.log10(0.4)));  // the slider is logarithmic
  const contrast = await waitValues(page, { contrast: 0.4 }, 'contrast 0.4');
  check(readoutOf(contrast, 'contrast') === '0.4', `the contrast readout shows "${readoutOf(contrast, 'contrast')}", not 0.4`);
  const flat = await waitCamera(page, `with less than 0.6 of its spread at contrast 1 (${fmtStats(base2)}) and its mean nearer 128`,
    (s) => s.sd < 0.6 * base2.sd && Math.abs(s.mean - 128) < Math.abs(base2.mean - 128) - 0.3 * Math.abs(base2.mean - 128));
  await screenshot(state, page, '03-contrast');
  ok(`contrast 0.4 (the run echoed ${valueOf(contrast, 'contrast')}): the camera layer went from ${fmtStats(base2)} to ${fmtStats(flat)}`);

  // ------------------------------------------------ 4. min score 1: no detections; defaults: back
  await page.evaluate(() => {
    for (const box of document.querySelectorAll('[data-overlay]')) {
      if (!box.checked) { box.checked = true; box.dispatchEvent(new Event('change')); }
    }
  });
  await page.click('#vision-defaults');
  await waitValues(page, DEFAULTS, 'the defaults after "defaults"');
  await waitDetections(page, REAL, 'the markers at the defaults');
  await page.locator('#vision-min_score').fill('1');
  await waitValues(page, { min_score: 1 }, 'min score 1');
  const none = await waitDetections(page, [], 'no marker with min score 1', 10);
  const noneShown = await poll('the Vision section to say that no marker is found', async () => {
    const f = (await visionShown(page)).found;
    return /^found no marker/.test(f) && f;
  });
  await screenshot(state, page, '04-min-score-1');
  const sentBeforeDefaults = state.sent['page 1'].length;
  await page.click('#vision-defaults');
  const back = await waitValues(page, DEFAULTS, 'the defaults after "defaults"');
  const defaultsRequests = state.sent['page 1'].slice(sentBeforeDefaults);
  check(defaultsRequests.length === 1 && defaultsRequests[0].parameters.length === 6,
    `"defaults" sent ${JSON.stringify(defaultsRequests.map((r) => r.parameters))}, not one request with the six settings`);
  check(back.yaml === DEFAULT_YAML, `after "defaults" the YAML snippet is "${back.yaml}"`);
  const again = await waitDetections(page, REAL, 'the markers back after "defaults"');
  ok(`min score 1: frame ${none.frame} and the 9 before it without a marker ("${noneShown}"); "defaults" (one request ` +
     `with the six) brought every setting back and the markers ${again.ids.join(', ')} with them (frame ${again.frame})`);

  // ------------------------------------------------ 5. refusals
  const refused = await page.evaluate(() => window.rilbed.vision.set({ threshold: 1000 }));
  check(refused.refused.join() === 'vision.threshold' && refused.values['vision.threshold'] === DEFAULTS.threshold,
    `threshold 1000: the page has ${JSON.stringify(refused)}`);
  const refusedShown = await poll('the page to show the refusal of threshold 1000 (in the Vision section and the console\'s line)', async () => {
    const s = await visionShown(page);
    state.lastShown = s;
    return /^✗ .+/.test(s.reply) && !/✗ refused \(/.test(s.reply) && /^server: /.test(s.consoleReply) && s;
  }, { describe: () => JSON.stringify({ reply: state.lastShown.reply, console: state.lastShown.consoleReply }) });
  check(refusedShown.replyColour === 'rgb(179, 38, 30)', `the refusal is written in ${refusedShown.replyColour}, not the page's danger red`);
  check(readoutOf(refusedShown, 'threshold') === String(DEFAULTS.threshold), `after the refusal the threshold readout shows "${readoutOf(refusedShown, 'threshold')}"`);
  await screenshot(state, page, '05-refused');
  const crossed = await page.evaluate(() => window.rilbed.vision.set({ min_diameter_px: 500 }));
  check(crossed.refused.join() === 'vision.min_diameter_px' && crossed.values['vision.min_diameter_px'] === DEFAULTS.min_diameter_px,
    `min diameter 500 (above the max, 480): the page has ${JSON.stringify(crossed)}`);
  const crossedShown = await poll('the page to show the refusal of min diameter 500', async () => {
    const s = await visionShown(page);
    return s.reply !== refusedShown.reply && /^✗ .+/.test(s.reply) && s;
  });
  ok(`threshold 1000 refused: "${refusedShown.reply}" (console line "${refusedShown.consoleReply}"); ` +
     `min diameter 500 above the max refused: "${crossedShown.reply}"; the values stayed`);

  // ------------------------------------------------ 6. a second page follows
  const page2 = await openVisionPage(state, context, 'page 2', mixed.url);
  await waitValues(page2, DEFAULTS, 'the defaults on page 2');
  await page2.locator('#vision-threshold').fill('40');
  await waitValues(page2, { threshold: 40 }, 'threshold 40 on page 2');
  const followed = await waitValues(page, { threshold: 40 }, 'threshold 40 on page 1 (set by page 2)');
  const slider1 = followed.rows.find((r) => r.name === 'vision.threshold');
  check(slider1.readout === '40' && slider1.slider === '40', `page 1's threshold shows readout "${slider1.readout}", slider ${slider1.slider} after page 2 set 40`);
  await page2.click('#vision-defaults');
  await waitValues(page, DEFAULTS, 'the defaults on page 1 (set by page 2)');
  await page2.close();
  ok('page 2 set threshold 40: page 1 shows it (readout and slider), and page 2\'s "defaults" too');

  // ------------------------------------------------ 7. a run without a camera
  const sim = await startRilbed(state, binary, simScenario, { label: 'sim' });
  const simPage = await openVisionPage(state, context, 'sim page', sim.url);
  const simShown = await poll('the Vision section of the run without a camera to be greyed with a reason', async () => {
    const s = await visionShown(simPage);
    state.lastSim = s;
    return s.greyed && s.reason && !/asking/.test(s.reason) && s;
  }, { describe: () => JSON.stringify(state.lastSim) });
  check(/camera/.test(simShown.reason), `the reason "${simShown.reason}" does not mention the camera`);
  check(simShown.rows.every((r) => r.disabled) && simShown.defaultsDisabled, 'a control of the Vision section is enabled in a run without a camera');
  check(simShown.yaml === '', `a run without a camera shows the YAML snippet "${simShown.yaml}"`);
  await screenshot(state, simPage, '06-no-camera');
  ok(`${path.basename(simScenario)} (no camera): the Vision section is greyed, its controls disabled: "${simShown.reason}"`);

  check(state.pageErrors.length === 0, `the pages logged ${state.pageErrors.length} errors:\n  ${state.pageErrors.join('\n  ')}`);
  ok('no console error and no uncaught exception on any page');
}

run(main, { name: 'vision_test', watchdogMs: WATCHDOG_MS });
