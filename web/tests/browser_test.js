#!/usr/bin/env node
// The web panel in a real browser: Debian's Chromium, driven by playwright-core,
// against `rilbed run --gui` with emulated real robots.
//
//   node web/tests/browser_test.js RILBED MIXED_SCENARIO SIM_SCENARIO [ARTEFACT_DIR]
//
// MIXED_SCENARIO is scenarios/convoy_mixed.yaml: the test writes a copy of it to a temp
// folder whose robots are its own (1-3 a virtual convoy, 4 real and standing still at a
// known pose so that the page can drive it, 5 real, 6-8 virtual, all but the convoy
// standing still) and runs `RILBED run COPY --realtime --duration 300 --gui --gui-port 0
// --out TMPDIR`. SIM_SCENARIO (scenarios/convoy_sim.yaml, no real robots) is run the same
// way for the real-time factor, which real robots pin to 1. It checks:
//   1. the page loads with the token (without it: 401), connects, shows the run;
//   2. the live view draws every robot where /rilbed/poses (and the run's own
//      trajectories.csv) says it is: red (#d22828) strokes around a virtual robot, blue
//      (#2456c7) around a real one, neither far from every robot;
//   3. Pause pauses (banner, status, events.csv "paused by gui"), Start resumes; while
//      paused, zooming draws the trails moved with the view, lined up with the trails laid anew;
//   4. the real-time factor slider is disabled with real robots and sets the factor of a
//      run without them (status rt_factor 2, the clock running about twice as fast);
//   5. manual driving: Take robot 4, hold ArrowUp: it drives forward; let go: it stops
//      (events.csv "robot 4 driven 0 0");
//   6. closing the tab while driving stops the robot (seen from a second page);
//   7. Exit (confirmed) ends the run: the banner says so, rilbed exits 0 and says
//      "robot 4 (emulated): last speed 0 0";
//   8. robot bodies: a run of its own (a scenario written to the temp folder: a square
//      robot, `model: square`; an e-puck, `model: robots/epuck.yaml`; a Khepera; a wedge,
//      an e-puck with a `body:` override) whose /rilbed/world gives each its body, which
//      the live view draws: red on each body's edge (the square's corners, the e-puck's
//      35 mm rim), none 5 px inside or outside it; "Start from this run" keeps them as
//      `body:` and `wheels:`, and rilbed run accepts that scenario;
// and that no page logged a console error or threw, all the test long. Screenshots of
// the important moments go to $RILBED_ARTIFACTS, else ARTEFACT_DIR (CTest passes
// BUILD/web-artifacts), else a temp folder; their paths are printed. Every wait polls
// with a deadline; on any failure it says what it was waiting for, shows the end of
// rilbed's output, kills rilbed and the browser and exits 1. CTest runs it as
// web_browser (label e2e); `./run test` installs its npm packages and Chromium.
'use strict';

const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');
const {
  ok, check, sleep, poll, describeExit, startRilbed, commandLine, checkBinary, checkScenario,
  tempFolder, withRobots, requirePlaywright, launchBrowser, newContext, openPage, useArtefacts, screenshot, run,
} = require('./support');

const WATCHDOG_MS = 280000;      // the whole test (CTest's TIMEOUT is 300 s)
const VIRTUAL_RGB = [0xd2, 0x28, 0x28];
const REAL_RGB = [0x24, 0x56, 0xc7];
const COLOUR_TOLERANCE = 40;     // per channel: antialiasing and the camera image under the strokes
const ROBOT_RADIUS_M = 0.0275;   // a Khepera
const DRIVEN = 4;                // the robot the page drives
const DRIVEN_POSE = [0.25, 0.6, 0]; // x_m, y_m, theta_deg: room ahead of it (the field is 1.5 m wide)
const TRAIL_ROBOT = 8;            // a standing virtual robot driven out and back for the trails
const STILL_M = 0.003;           // two readings 0.5 s apart closer than this: standing
const MOVED_M = 0.02;            // a clear move
const STOP_WITHIN_S = 5;         // a stop is seen about 1 s after the key (0.5 s of it the two readings)

const dist = (a, b) => Math.hypot(a.x - b.x, a.y - b.y);
const mm = (m) => `${(m * 1000).toFixed(1)} mm`;

// ---------------------------------------------------------------- the scenarios
// The mixed scenario's copy: its field, timing, camera and safety as shipped, its robots
// this test's own. Robot 4 has no controller (the page drives it) and a known pose; the
// others but the convoy stand still, so that nothing drives into robot 4 or its view.
function mixedScenarioCopy(text) {
  const robots = `robots:
  - ids: 1-3
    pose: random
    controller: convoy
    noise: {slip_sd: 0.02}
  - id: ${DRIVEN}
    kind: real
    link: {emulate: true}
    pose: [${DRIVEN_POSE.join(', ')}]
    controller: none
  - id: 5
    kind: real
    link: {emulate: true}
    pose: random
    controller: none
  - ids: 6-8
    pose: random
    controller: none`;
  return withRobots(text, robots);
}

// ---------------------------------------------------------------- the run's files
// events.csv's lines (flushed by the run at every event).
function events(runDir) {
  const file = path.join(runDir, 'events.csv');
  return fs.existsSync(file) ? fs.readFileSync(file, 'utf8').split('\n').filter((l) => l) : [];
}
function waitForEvent(run, what, test) {
  return poll(`a line ${what} in ${path.join(run.runDir, 'events.csv')}`, () => events(run.runDir).find(test),
    { everyMs: 200, describe: () => events(run.runDir).slice(-6).join(' | ') });
}
// The robot's drive events ("robot 4 driven L R for S s by gui ...") as [index, left, right, line].
function driveEvents(runDir, id) {
  const re = new RegExp(`,console,${id},0,robot ${id} driven (-?\\d+) (-?\\d+) for `);
  return events(runDir).map((l, i) => [i, re.exec(l), l]).filter(([, m]) => m).map(([i, m, l]) => [i, Number(m[1]), Number(m[2]), l]);
}

// Waits until robot `id`'s drive events after the first `from` are a drive at `speed`
// both wheels followed, last, by a stop (0 0); returns those two lines.
function driveThenStop(runDir, id, from, speed) {
  return poll(`events.csv to record robot ${id} driven ${speed} ${speed}, then (last) driven 0 0`, () => {
    const d = driveEvents(runDir, id).slice(from);
    const go = d.findIndex(([, l, r]) => l === speed && r === speed);
    const last = d[d.length - 1];
    return go >= 0 && d.length - 1 > go && last[1] === 0 && last[2] === 0 && [d[go][3], last[3]];
  }, { everyMs: 200, describe: () => driveEvents(runDir, id).slice(from).map((d) => d[3]).join(' | ') || 'none' });
}

// ---------------------------------------------------------------- the page
// A page on `url` (support.js's openPage) whose confirm dialogs are accepted (and kept in state.dialogs).
const openDrivenPage = (state, context, label, url) => openPage(state, context, label, url,
  (page) => page.on('dialog', (d) => { state.dialogs.push(`${label}: ${d.type()} "${d.message()}"`); d.accept(); }));

const statusOf = (page) => page.evaluate(() => window.rilbed.run.status);
const poseOf = (page, id) => page.evaluate((id) => {
  const p = window.rilbed.run.poses;
  const r = p && p.robots.find((q) => q.id === id);
  return r ? { t: p.t_s, x: r.x_m, y: r.y_m, theta: r.theta_rad, seen: r.seen, health: r.health } : null;
}, id);

// Waits until robot `id` stands: two readings 0.5 s apart (of fresh poses) closer than STILL_M.
async function waitStill(page, id, what) {
  const started = Date.now();
  let last = '';
  const pose = await poll(`robot ${id} to stand still (${what}): two readings 0.5 s apart within ${mm(STILL_M)}`, async () => {
    const a = await poseOf(page, id);
    await sleep(500);
    const b = await poseOf(page, id);
    if (!a || !b) return null;
    last = `(${a.x.toFixed(4)}, ${a.y.toFixed(4)}) at t ${a.t.toFixed(2)} s, then (${b.x.toFixed(4)}, ${b.y.toFixed(4)}) at t ${b.t.toFixed(2)} s`;
    return b.t > a.t && dist(a, b) < STILL_M && b;
  }, { everyMs: 0, describe: () => last });
  return { pose, seconds: (Date.now() - started) / 1000 };
}

// Samples the live view around every robot: in one animation frame, each robot's
// projected position and the count of pixels of the virtual and the real colour within
// 1.6 radii (+ 4 px) of it, and the same for the spot of the field farthest from every robot.
function sampleView(page) {
  return page.evaluate(async ({ VIRTUAL_RGB, REAL_RGB, COLOUR_TOLERANCE, ROBOT_RADIUS_M }) => {
    await new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
    const R = window.rilbed;
    const canvas = document.getElementById('view');
    const dpr = window.devicePixelRatio || 1;
    const image = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height);
    const like = (d, i, rgb) => rgb.every((c, k) => Math.abs(d[i + k] - c) <= COLOUR_TOLERANCE) && d[i + 3] > 200;
    const count = (x_m, y_m) => {
      const [u, v] = R.project(x_m, y_m);
      const [u2, v2] = R.project(x_m + 0.01, y_m);
      const radiusCss = ROBOT_RADIUS_M * Math.hypot(u2 - u, v2 - v) / 0.01;
      const half = (1.6 * radiusCss + 4) * dpr;
      const cx = u * dpr, cy = v * dpr;
      let virtual = 0, real = 0;
      for (let y = Math.max(0, Math.floor(cy - half)); y <= Math.min(image.height - 1, Math.ceil(cy + half)); y++) {
        for (let x = Math.max(0, Math.floor(cx - half)); x <= Math.min(image.width - 1, Math.ceil(cx + half)); x++) {
          const i = 4 * (y * image.width + x);
          if (like(image.data, i, VIRTUAL_RGB)) virtual++;
          else if (like(image.data, i, REAL_RGB)) real++;
        }
      }
      const inside = u >= 0 && v >= 0 && u <= canvas.clientWidth && v <= canvas.clientHeight;
      return { u, v, radiusCss, virtual, real, inside };
    };
    const poses = R.run.poses;
    const robots = poses.robots.map((r) => ({ id: r.id, real: r.real, seen: r.seen, x: r.x_m, y: r.y_m, ...count(r.x_m, r.y_m) }));
    // The free spot: a grid point of the field (5 cm from its edges) farthest from every robot.
    const W = R.run.world;
    let free = null;
    for (let x = 0.1; x <= W.width_m - 0.1; x += 0.05) {
      for (let y = 0.1; y <= W.height_m - 0.1; y += 0.05) {
        const d = Math.min(...poses.robots.map((r) => Math.hypot(r.x_m - x, r.y_m - y)));
        if (!free || d > free.d) free = { x, y, d };
      }
    }
    free = { ...free, ...count(free.x, free.y) };
    return { t: poses.t_s, dpr, width: canvas.width, height: canvas.height, cssWidth: canvas.clientWidth,
      cssHeight: canvas.clientHeight, camera: !!(R.run.image && R.run.calibration), robots, free };
  }, { VIRTUAL_RGB, REAL_RGB, COLOUR_TOLERANCE, ROBOT_RADIUS_M });
}

// While the view moves, the trails are the layer laid for the view before, moved and scaled
// (app.js drawTrails): seen on the canvas of a paused run, without the camera image (so that
// only the trails differ between frames). A wheel zoom (x1.57 about a point off the centre);
// the frame drawn then (A: the layer moved, stats.trailsMoved), the frame after the view
// rested (B: the layer laid anew for it, stats.trailsLaid) and the same view without trails
// (C). The trails' own pixels, A - C and B - C, in 4 x 4 blocks, must line up: their
// normalised correlation unshifted high and higher than at any shift of 2-8 blocks; a
// layer left where it was, or moved wrongly, lines up with nothing.
function trailsFollowTheView(page) {
  return page.evaluate(async () => {
    const frames = (n) => new Promise((resolve) => {
      const step = () => (--n <= 0 ? resolve() : requestAnimationFrame(step));
      requestAnimationFrame(step);
    });
    const rest = async () => { await new Promise((r) => setTimeout(r, 400)); await frames(2); };
    const canvas = document.getElementById('view'), g = canvas.getContext('2d');
    const grab = () => g.getImageData(0, 0, canvas.width, canvas.height).data;
    const overlay = (name, on) => {
      const box = document.querySelector(`input[data-overlay="${name}"]`);
      if (box.checked !== on) box.click();
    };
    const stats = window.rilbed.stats;
    overlay('camera', false); overlay('trails', true);
    document.getElementById('fit').click();
    await rest();
    const r = canvas.getBoundingClientRect();
    const before = { moved: stats.trailsMoved, laid: stats.trailsLaid };
    const A = await new Promise((resolve) => {
      canvas.dispatchEvent(new WheelEvent('wheel', { deltaY: -300, clientX: r.left + 0.3 * r.width, clientY: r.top + 0.6 * r.height,
        bubbles: true, cancelable: true }));
      requestAnimationFrame(() => resolve(grab())); // after the page's draw of this frame
    });
    const moved = stats.trailsMoved - before.moved;
    await rest();
    const laid = stats.trailsLaid - before.laid;
    const B = grab();
    overlay('trails', false); await frames(2);
    const C = grab();
    overlay('trails', true); overlay('camera', true);
    document.getElementById('fit').click();
    // |X - C| summed over the colour channels, in 4 x 4 blocks.
    const K = 4, bw = Math.floor(canvas.width / K), bh = Math.floor(canvas.height / K);
    const blocks = (X) => {
      const out = new Float64Array(bw * bh);
      for (let y = 0; y < bh * K; ++y) {
        for (let x = 0; x < bw * K; ++x) {
          const i = 4 * (y * canvas.width + x);
          out[Math.floor(y / K) * bw + Math.floor(x / K)] += Math.abs(X[i] - C[i]) + Math.abs(X[i + 1] - C[i + 1]) + Math.abs(X[i + 2] - C[i + 2]);
        }
      }
      return out;
    };
    const a = blocks(A), b = blocks(B);
    const ncc = (dx, dy) => {
      let sab = 0, saa = 0, sbb = 0;
      for (let y = Math.max(0, -dy); y < Math.min(bh, bh - dy); ++y) {
        for (let x = Math.max(0, -dx); x < Math.min(bw, bw - dx); ++x) {
          const p = a[(y + dy) * bw + x + dx], q = b[y * bw + x];
          sab += p * q; saa += p * p; sbb += q * q;
        }
      }
      return saa && sbb ? sab / Math.sqrt(saa * sbb) : 0;
    };
    let shifted = { ncc: -1 };
    for (let dy = -8; dy <= 8; ++dy) {
      for (let dx = -8; dx <= 8; ++dx) {
        if (Math.max(Math.abs(dx), Math.abs(dy)) < 2) continue;
        const c = ncc(dx, dy);
        if (c > shifted.ncc) shifted = { ncc: c, dx, dy };
      }
    }
    let trailBlocks = 0;
    for (const q of b) if (q > 0) ++trailBlocks;
    return { moved, laid, aligned: ncc(0, 0), shifted, trailBlocks };
  });
}

// trajectories.csv's rows (t_s,id,x_m,y_m,theta_deg,behaviour) by robot.
function trajectories(runDir) {
  const file = path.join(runDir, 'trajectories.csv');
  const byId = new Map();
  if (!fs.existsSync(file)) return byId;
  for (const line of fs.readFileSync(file, 'utf8').split('\n').slice(1)) {
    const [t, id, x, y] = line.split(',').map(Number);
    if (!Number.isFinite(y)) continue;
    if (!byId.has(id)) byId.set(id, []);
    byId.get(id).push({ t, x, y });
  }
  return byId;
}

// ---------------------------------------------------------------- robot bodies
// Robots of parts (robots/*.yaml named by `model:`, a body override): a square (robots/
// square.yaml), an e-puck (a 35 mm disc), a Khepera (no model: 27.5 mm) and a wedge (an
// e-puck with a body override, three points), all standing (controller none) well apart,
// in a field without a camera.
const SQUARE_OUTLINE = [[0.035, 0.035], [-0.035, 0.035], [-0.035, -0.035], [0.035, -0.035]]; // robots/square.yaml's
const WEDGE_OUTLINE = [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]];
// Each: its entry's keys (`yaml`), and the body and wheels the run must give it.
const BODY_ROBOTS = [
  { id: 1, yaml: ['model: square'], pose: [0.2, 0.3, 30], outline: SQUARE_OUTLINE, wheels: { base_m: 0.06, radius_m: 0.016 } },
  { id: 2, yaml: ['model: robots/epuck.yaml'], pose: [0.45, 0.3, 0], radius: 0.035, wheels: { base_m: 0.053, radius_m: 0.0205 } },
  { id: 3, yaml: [], pose: [0.65, 0.3, 0], radius: 0.0275, wheels: null },
  { id: 4, yaml: ['model: epuck', 'body: {outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]]}', 'wheels: {base_m: 0.05, radius_m: 0.012}'],
    pose: [0.85, 0.3, 90], outline: WEDGE_OUTLINE, wheels: { base_m: 0.05, radius_m: 0.012 } },
];
function bodiesScenario() {
  const robots = BODY_ROBOTS.map((r) => [`  - id: ${r.id}`, ...r.yaml.map((l) => `    ${l}`), `    pose: [${r.pose.join(', ')}]`,
    '    controller: none'].join('\n'));
  return `# browser_test.js: robots of parts, drawn with their own bodies.
name: bodies
description: A square robot, an e-puck, a Khepera and a wedge (an e-puck with a body override), standing.
field: {width_m: 1.0, height_m: 0.6, walls: true}
duration_s: 300
robots:
${robots.join('\n')}
`;
}

// The live view around each robot of BODY_ROBOTS, in one animation frame: red pixels
// (VIRTUAL_RGB) near points on its body's edge (each must have some), and near points
// OFF_PX inside and outside its edge (none may): a body drawn as a Khepera's disc, or
// as any other shape, fails both. Directions within 35 degrees of the heading (the
// heading mark runs there) are left out. Points are robot-frame [x, y] metres, turned and
// moved to the robot's pose (trajectories.csv's start, which controller none keeps).
function sampleBodies(page) {
  return page.evaluate(({ robots, VIRTUAL_RGB, COLOUR_TOLERANCE }) => {
    const R = window.rilbed;
    const canvas = document.getElementById('view');
    const dpr = window.devicePixelRatio || 1;
    const image = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height);
    const red = (i) => VIRTUAL_RGB.every((c, k) => Math.abs(image.data[i + k] - c) <= COLOUR_TOLERANCE) && image.data[i + 3] > 200;
    const HALF_PX = 1.5, OFF_PX = 5; // the window's half size and the off-edge distance, CSS pixels
    const redNear = ([x, y]) => {
      const [u, v] = R.project(x, y);
      let n = 0;
      for (let py = Math.floor((v - HALF_PX) * dpr); py <= Math.ceil((v + HALF_PX) * dpr); ++py) {
        for (let px = Math.floor((u - HALF_PX) * dpr); px <= Math.ceil((u + HALF_PX) * dpr); ++px) {
          if (px >= 0 && py >= 0 && px < image.width && py < image.height && red(4 * (py * image.width + px))) ++n;
        }
      }
      return n;
    };
    const [u0, v0] = R.project(0, 0), [u1, v1] = R.project(0.01, 0);
    const pxPerM = Math.hypot(u1 - u0, v1 - v0) / 0.01, off = OFF_PX / pxPerM;
    return robots.map((r) => {
      const [x0, y0, th] = r.pose, a = (th * Math.PI) / 180, c = Math.cos(a), s = Math.sin(a);
      const field = ([fx, fy]) => [x0 + c * fx - s * fy, y0 + s * fx + c * fy];
      const awayFromMark = ([fx, fy]) => Math.abs(Math.atan2(fy, fx)) > (35 * Math.PI) / 180;
      // On the edge: the outline's corners and the middles of its sides, or 8 points round the disc.
      let edge, sides;
      if (r.outline) {
        sides = r.outline.map((p, k) => { const q = r.outline[(k + 1) % r.outline.length]; return [(p[0] + q[0]) / 2, (p[1] + q[1]) / 2]; });
        edge = [...r.outline, ...sides];
      } else {
        sides = Array.from({ length: 8 }, (_, k) => [r.radius * Math.cos((k * Math.PI) / 4), r.radius * Math.sin((k * Math.PI) / 4)]);
        edge = sides;
      }
      edge = edge.filter(awayFromMark);
      sides = sides.filter(awayFromMark);
      // Off the edge: from each side's middle (or the disc's points), OFF_PX along the normal,
      // which for these (a disc, outlines around the centre) is along the ray from the centre
      // for a disc and the side's own normal for an outline.
      const offPoints = (sign) => sides.map((p, k) => {
        let nx, ny;
        if (r.outline) {
          const q = r.outline[k], w = r.outline[(k + 1) % r.outline.length];
          const len = Math.hypot(w[0] - q[0], w[1] - q[1]);
          nx = (w[1] - q[1]) / len; ny = -(w[0] - q[0]) / len; // outwards: the outline is counter-clockwise
        } else {
          const len = Math.hypot(p[0], p[1]);
          nx = p[0] / len; ny = p[1] / len;
        }
        return [p[0] + sign * off * nx, p[1] + sign * off * ny];
      });
      const count = (pts) => pts.map((p) => redNear(field(p)));
      return { id: r.id, pxPerM, edge: count(edge), inside: count(offPoints(-1)), outside: count(offPoints(1)) };
    });
  }, { robots: BODY_ROBOTS, VIRTUAL_RGB, COLOUR_TOLERANCE });
}

async function checkBodies(state, binary) {
  const scenario = path.join(state.tmp, 'bodies.yaml');
  fs.writeFileSync(scenario, bodiesScenario());
  console.log(`# ${scenario}: ${BODY_ROBOTS.map((r) => `robot ${r.id} {${r.yaml.join(', ')}}`).join(', ')}`);
  const bodies = await startRilbed(state, binary, scenario, { label: 'bodies' });
  const context = await newContext(state, { viewport: { width: 1280, height: 900 }, deviceScaleFactor: 2 });
  const page = await openPage(state, context, 'bodies page', bodies.url);
  // What /rilbed/world says of each robot's body.
  const world = await page.evaluate(() => window.rilbed.run.world.robots.map((r) => ({ id: r.id, body: r.body || null })));
  const near = (a, b) => Math.abs(a - b) < 1e-6;
  const samePoints = (pts, want) => pts.length === want.length && pts.every((p, k) => near(p.x_m, want[k][0]) && near(p.y_m, want[k][1]));
  for (const r of BODY_ROBOTS) {
    const b = world.find((w) => w.id === r.id)?.body;
    const described = JSON.stringify(b);
    if (!b && !r.wheels) continue; // a Khepera may go without
    if (r.outline) {
      check(b && samePoints(b.outline, r.outline) && near(b.radius_m, Math.max(...r.outline.map(([x, y]) => Math.hypot(x, y)))),
        `/rilbed/world gives robot ${r.id} the body ${described}, not the outline ${JSON.stringify(r.outline)}`);
    } else {
      check(b && b.outline.length === 0 && near(b.radius_m, r.radius), `/rilbed/world gives robot ${r.id} the body ${described}, not a disc of ${r.radius} m`);
    }
    if (r.wheels) {
      check(near(b.wheel_base_m, r.wheels.base_m) && near(b.wheel_radius_m, r.wheels.radius_m),
        `/rilbed/world gives robot ${r.id} the wheels of ${described}, not ${JSON.stringify(r.wheels)}`);
    }
  }
  ok(`/rilbed/world gives each robot its body: ${world.map((w) => `${w.id} ${w.body ? `${w.body.name} ` +
    (w.body.outline.length ? `${w.body.outline.length}-point outline` : `disc ${w.body.radius_m} m`) : 'none (a Khepera)'}`).join(', ')}`);

  // The live view draws them: each robot's edge red where its body's edge is, nothing red
  // just inside or outside it.
  await poll('the bodies page to draw the four robots with their outlines and wheels (stats.outlines 2, stats.wheels 4)',
    () => page.evaluate(() => window.rilbed.stats.outlines === 2 && window.rilbed.stats.wheels === 4),
    { describe: () => page.evaluate(() => JSON.stringify(window.rilbed.stats)) });
  const shapes = await poll('every robot drawn with its own body: red on its edge, none just inside or outside it', async () => {
    await page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve))));
    const s = await sampleBodies(page);
    state.lastBodies = s;
    return s.every((r) => r.edge.every((n) => n > 0) && r.inside.every((n) => n === 0) && r.outside.every((n) => n === 0)) && s;
  }, { everyMs: 300, ms: 15000, describe: () => JSON.stringify(state.lastBodies) });
  await screenshot(state, page, '07-bodies');
  const view = path.join(state.artifacts, `${state.shotPrefix}-07-bodies-view.png`);
  await page.locator('#view').screenshot({ path: view });
  state.screenshots.push(view);
  console.log(`# screenshot ${view}`);
  ok(`the live view draws each robot's own body (${shapes[0].pxPerM.toFixed(0)} px/m): ` +
     shapes.map((s) => `${s.id} red at ${s.edge.length} points of its edge, none at ${s.inside.length + s.outside.length} points just off it`).join('; '));

  // The editor started from this run keeps the bodies as body: and wheels: overrides
  // (the Khepera without), and rilbed run accepts the scenario.
  await page.click('#editor-panel > summary');
  await page.locator('#editor-from-run').scrollIntoViewIfNeeded();
  await page.click('#editor-from-run');
  const doc = await poll('the editor to hold the run\'s 4 robots', () => page.evaluate(() => {
    const d = window.rilbedEditor.doc;
    return d.robots?.length === 4 && JSON.parse(JSON.stringify(d));
  }));
  const problems = await page.evaluate(() => window.rilbedEditor.problems());
  for (const r of BODY_ROBOTS) {
    const e = doc.robots.find((q) => q.id === r.id);
    const want = r.outline ? { outline_m: r.outline } : r.wheels ? { radius_m: r.radius } : undefined;
    check(JSON.stringify(e.body) === JSON.stringify(want) && JSON.stringify(e.wheels) === JSON.stringify(r.wheels ?? undefined),
      `"Start from this run" made robot ${r.id} ${JSON.stringify(e)}, not one with body ${JSON.stringify(want)} and wheels ${JSON.stringify(r.wheels)}`);
  }
  check(problems.length === 0, `the editor finds problems in the scenario started from the bodies run: ${problems.join(' ')}`);
  await page.locator('#editor-canvas').scrollIntoViewIfNeeded();
  const editorShot = path.join(state.artifacts, `${state.shotPrefix}-08-bodies-editor.png`);
  await page.locator('#editor-canvas').screenshot({ path: editorShot });
  state.screenshots.push(editorShot);
  console.log(`# screenshot ${editorShot}`);
  const saved = path.join(state.tmp, 'bodies-from-run.yaml');
  fs.writeFileSync(saved, await page.evaluate(() => window.rilbedEditor.yaml));
  const accepted = spawnSync(binary, ['run', saved, '--fast', '--duration', '1', '--quiet', '--out', path.join(state.tmp, 'bodies-from-run')],
    { encoding: 'utf8', timeout: 60000 });
  check(accepted.status === 0, `rilbed run refuses the scenario the editor started from the bodies run (${accepted.error?.message || accepted.signal || `exit code ${accepted.status}`}):\n` +
    `${accepted.stderr}\n--- the file ---\n${fs.readFileSync(saved, 'utf8')}`);
  ok(`"Start from this run" keeps the bodies (${doc.robots.map((e) => `${e.id} ${e.body ? JSON.stringify(e.body) : 'a Khepera'}`).join(', ')}); ` +
     'no problem found, and rilbed run accepts it');
  await context.close();
  await bodies.child.kill();
}

// ---------------------------------------------------------------- the test
async function main(state) {
  const [binary, mixedScenario, simScenario, artefactArg] = commandLine('RILBED MIXED_SCENARIO SIM_SCENARIO [ARTEFACT_DIR]');
  const playwright = requirePlaywright();
  checkBinary(binary);
  checkScenario(mixedScenario);
  checkScenario(simScenario);

  state.dialogs = [];
  tempFolder(state, 'browser');
  useArtefacts(state, artefactArg, 'browser');

  const scenario = path.join(state.tmp, 'convoy_mixed_driven.yaml');
  fs.writeFileSync(scenario, mixedScenarioCopy(fs.readFileSync(mixedScenario, 'utf8')));
  console.log(`# ${scenario}: ${mixedScenario} with robot ${DRIVEN} real, controller none, at ` +
    `(${DRIVEN_POSE[0]} m, ${DRIVEN_POSE[1]} m, ${DRIVEN_POSE[2]} deg); 1-3 a convoy; 5 real, 6-8 virtual, standing`);

  const mixed = await startRilbed(state, binary, scenario, { label: 'mixed' });
  console.log(`# the page: ${mixed.url.replace(mixed.token, 'TOKEN')}`);

  await launchBrowser(state, playwright);
  // A device pixel ratio of 2: the view's canvas must be sized and sampled in device pixels.
  const context = await newContext(state, { viewport: { width: 1280, height: 900 }, deviceScaleFactor: 2 });

  // ------------------------------------------------ 1. the page, the token
  const base = `http://127.0.0.1:${mixed.port}`;
  for (const url of [`${base}/`, `${base}/?token=0123456789abcdef0123456789abcdef`, `${base}/app.js`]) {
    const response = await fetch(url);
    check(response.status === 401, `GET ${url.replace(base, '')} without the token answered ${response.status}, not 401`);
  }
  const page = await openDrivenPage(state, context, 'page 1', mixed.url);
  const title = await page.title();
  const shown = await page.evaluate(() => ({
    scenario: document.getElementById('scenario').textContent,
    options: [...document.querySelectorAll('#drive-robot option')].map((o) => o.textContent),
  }));
  const world = await page.evaluate(() => window.rilbed.run.world);
  check(title === 'rilbed', `the page's title is "${title}"`);
  check(shown.scenario === world.scenario && world.scenario === 'convoy_mixed',
    `the page shows scenario "${shown.scenario}", /rilbed/world says "${world.scenario}"`);
  check(world.robots.length === 8, `/rilbed/world has ${world.robots.length} robots, not 8`);
  await poll('the agents table to list the 8 robots', () => page.evaluate(() => document.querySelectorAll('#agents tbody tr').length === 8));
  check(shown.options.join() === '1,2,3,4 (real),5 (real),6,7,8', `the robots to drive are ${shown.options.join(', ')}`);
  ok(`the page loads with the token (title "${title}", scenario "${shown.scenario}", robots to drive ` +
     `${shown.options.join(', ')}); without it / and /app.js answer 401, as does a wrong token`);

  // ------------------------------------------------ 2. the robots where the run says
  await poll('both real robots to be seen by the camera (poses: seen)', () => page.evaluate(() =>
    window.rilbed.run.poses.robots.filter((r) => r.real).every((r) => r.seen)));
  const view = await poll('a sample of the live view with every robot drawn in its colour', async () => {
    const v = await sampleView(page);
    state.lastView = v;
    return v.robots.every((r) => r.inside && (r.real ? r.real > 10 : r.virtual > 10)) && v;
  }, { everyMs: 300, describe: () => JSON.stringify(state.lastView) });
  check(view.dpr === 2 && view.width === Math.round(view.cssWidth * 2), `the canvas is ${view.width} device pixels for ` +
    `${view.cssWidth} CSS pixels at a device pixel ratio of ${view.dpr}`);
  check(view.free.d > 0.1, `the spot farthest from every robot is only ${view.free.d.toFixed(3)} m from one`);
  check(view.free.virtual === 0 && view.free.real === 0, `the free spot (${view.free.x.toFixed(2)}, ${view.free.y.toFixed(2)}) m, ` +
    `${view.free.d.toFixed(2)} m from every robot, has ${view.free.virtual} red and ${view.free.real} blue pixels`);
  const driven0 = view.robots.find((r) => r.id === DRIVEN);
  check(Math.hypot(driven0.x - DRIVEN_POSE[0], driven0.y - DRIVEN_POSE[1]) < 0.02,
    `robot ${DRIVEN} is at (${driven0.x.toFixed(3)}, ${driven0.y.toFixed(3)}), not at its start (${DRIVEN_POSE[0]}, ${DRIVEN_POSE[1]})`);
  // The run's own record: trajectories.csv at the time of that sample (flushed about once a second).
  const rows = await poll(`trajectories.csv to reach t = ${view.t.toFixed(2)} s for every robot`, () => {
    const byId = trajectories(mixed.runDir);
    return view.robots.every((r) => (byId.get(r.id) || []).some((s) => s.t >= view.t)) && byId;
  });
  const offsets = view.robots.map((r) => {
    const nearest = rows.get(r.id).reduce((a, b) => (Math.abs(b.t - view.t) < Math.abs(a.t - view.t) ? b : a));
    return { id: r.id, dt: Math.abs(nearest.t - view.t), d: dist(r, nearest) };
  });
  for (const o of offsets) {
    check(o.dt < 0.15 && o.d < 0.015, `robot ${o.id}: the page has it ${mm(o.d)} from trajectories.csv's row ` +
      `${o.dt.toFixed(3)} s from the page's poses (t ${view.t.toFixed(2)} s)`);
  }
  await screenshot(state, page, '01-live-view');
  ok(`the live view (${view.camera ? 'the camera image under it' : 'no camera image'}, ${view.width}x${view.height} device pixels at ratio ${view.dpr}) draws ` +
     `every robot where the run says: ${view.robots.map((r) => `${r.id} ${r.real ? 'blue' : 'red'} ${r.real ? r.real : r.virtual} px ` +
     `at (${r.u.toFixed(0)}, ${r.v.toFixed(0)})`).join(', ')}; none at the free spot (${view.free.x.toFixed(2)}, ` +
     `${view.free.y.toFixed(2)}) m; within ${mm(Math.max(...offsets.map((o) => o.d)))} of trajectories.csv`);

  // ------------------------------------------------ 3. Pause, Start
  const banner = () => page.evaluate(() => {
    const b = document.getElementById('banner');
    return { hidden: b.hidden, text: b.textContent, kind: b.className, state: window.rilbed.run.status.state,
      pause: document.getElementById('pause').disabled, start: document.getElementById('start').disabled };
  });
  check(!(await banner()).pause, 'the Pause button is disabled in a running real-time run');
  // Enough trail for the zoom check while paused. The convoy forms within seconds and then
  // stands, so a page that connected late (a loaded machine) saw little of its motion:
  // a robot that stands anyway is driven out and back by hand too. (A loaded machine, or
  // the ASan build, runs slowly: up to 150 s.)
  // Out and back until the trails have enough points: one trip leaves about 20, and a page
  // that saw nothing of the convoy's forming may need more than one (at most four).
  const trailPoints = () => page.evaluate(() => {
    let k = 0;
    for (const t of window.rilbed.run.trails.values()) k += t.length;
    return k;
  });
  await page.selectOption('#drive-robot', String(TRAIL_ROBOT));
  await page.click('#drive-take');
  for (let trip = 0; trip < 4 && (await trailPoints()) < 40; ++trip) {
    for (const key of ['ArrowUp', 'ArrowDown']) {
      await page.keyboard.down(key);
      const from = await poseOf(page, TRAIL_ROBOT);
      await poll(`robot ${TRAIL_ROBOT} to move 10 cm while ${key} is held (for the trails)`, async () =>
        dist(await poseOf(page, TRAIL_ROBOT), from) > 0.1, { ms: 60000 });
      await page.keyboard.up(key);
    }
  }
  await page.click('#drive-release');
  await poll('the robots to leave 40 trail points (for the zoom check)', async () => {
    const k = await trailPoints();
    return k >= 40 && k;
  }, { ms: 150000, describe: () => page.evaluate(() => JSON.stringify([...window.rilbed.run.trails].map(([id, t]) => [id, t.length]))) });
  await page.click('#pause');
  const paused = await poll('status "paused" and the banner saying so after Pause', async () => {
    const b = await banner();
    return b.state === 'paused' && !b.hidden && /Paused/.test(b.text) && !b.start && b;
  }, { describe: async () => JSON.stringify(await banner()) });
  const pausedLine = await waitForEvent(mixed, '",console,0,0,paused by gui 127.0.0.1:..."', (l) => /,console,0,0,paused by gui 127\.0\.0\.1:\d+$/.test(l));
  const t1 = (await statusOf(page)).t_s;
  await sleep(1000);
  const t2 = (await statusOf(page)).t_s;
  check(t2 === t1, `the clock ran on while paused (t ${t1} s, then ${t2} s)`);
  await screenshot(state, page, '02-paused');
  const follow = await trailsFollowTheView(page);
  check(follow.trailBlocks >= 8, `too few trail pixels to compare (${follow.trailBlocks} blocks): did the convoy not move?`);
  check(follow.moved >= 1 && follow.laid >= 1, `zooming did not draw the trail layer moved, then laid anew (${JSON.stringify(follow)})`);
  check(follow.aligned >= 0.6 && follow.aligned > follow.shifted.ncc + 0.1,
    `the trails drawn while zooming do not line up with the trails laid for the view: ${JSON.stringify(follow)}`);
  ok(`zooming: the trail layer moved with the view (${follow.moved} frame(s)), then laid anew; ` +
     `the two line up (correlation ${follow.aligned.toFixed(2)} unshifted, at most ${follow.shifted.ncc.toFixed(2)} shifted, ` +
     `${follow.trailBlocks} blocks of trails)`);
  await page.click('#start');
  await poll('status "running" and no banner after Start', async () => {
    const b = await banner();
    return b.state === 'running' && b.hidden && b;
  }, { describe: async () => JSON.stringify(await banner()) });
  const resumedLine = await waitForEvent(mixed, '",console,0,0,resumed by gui ..."', (l) => /,console,0,0,resumed by gui 127\.0\.0\.1:\d+$/.test(l));
  await poll('the clock to run on after Start', async () => (await statusOf(page)).t_s > t2 + 0.2);
  ok(`Pause: banner "${paused.text}", status paused, clock standing at ${t1.toFixed(1)} s, events.csv "${pausedLine}"; ` +
     `Start: running again, banner hidden, "${resumedLine}"`);

  // ------------------------------------------------ 4. the real-time factor
  const mixedSlider = await page.evaluate(() => ({ disabled: document.getElementById('rt-slider').disabled,
    factor: window.rilbed.run.status.rt_factor, real: window.rilbed.run.status.real_robots }));
  check(mixedSlider.disabled, `the real-time factor slider is enabled in a run with ${mixedSlider.real} real robots`);
  check(mixedSlider.factor === 1, `the run with real robots runs at a factor of ${mixedSlider.factor}`);
  const sim = await startRilbed(state, binary, simScenario, { label: 'sim' });
  const simContext = await newContext(state, { viewport: { width: 1280, height: 900 } });
  const simPage = await openDrivenPage(state, simContext, 'sim page', sim.url);
  await poll('the slider to be enabled in the run without real robots', () => simPage.evaluate(() => !document.getElementById('rt-slider').disabled));
  const before = await statusOf(simPage);
  check(before.rt_factor === 1 && before.real_robots === 0, `the sim run starts at factor ${before.rt_factor} with ${before.real_robots} real robots`);
  await simPage.locator('#rt-slider').fill(String(Math.log10(2).toFixed(2)));  // 0.30: 10^0.3 = 1.995, shown and sent as 2
  const factorLine = await waitForEvent(sim, '"real-time factor 2 set by gui ..."', (l) => /,console,0,0,real-time factor 2 set by gui /.test(l));
  // The clock (the poses' time, 10 a second): about twice as fast as the wall's.
  const simT = () => simPage.evaluate(() => window.rilbed.run.poses.t_s);
  const w0 = Date.now(), s0 = await simT();
  await poll('4 s of wall time with the sim run\'s clock', () => Date.now() - w0 >= 4000);
  const w1 = Date.now(), s1 = await simT();
  const ratio = (s1 - s0) / ((w1 - w0) / 1000);
  check(ratio > 1.6 && ratio < 2.4, `the sim run's clock ran ${(s1 - s0).toFixed(2)} s in ${((w1 - w0) / 1000).toFixed(2)} s of wall time (x${ratio.toFixed(2)}), not about x2`);
  // What the run says and the page shows (the status, sent about once a second).
  const fast = await poll('status rt_factor 2 after the slider, shown on the page (slider "2", state "running (×2)")', async () => {
    const s = await simPage.evaluate(() => ({ rt_factor: window.rilbed.run.status.rt_factor,
      shown: document.getElementById('rt-value').textContent, slider: document.getElementById('rt-slider').value,
      state: document.querySelector('dd[data-stat="state"]').textContent }));
    state.lastSim = s;
    return Math.abs(s.rt_factor - 2) < 0.01 && s.shown === '2' && s.state === 'running (×2)' && s;
  }, { describe: () => JSON.stringify(state.lastSim) });
  await screenshot(state, simPage, '03-rt-factor-2');
  sim.child.exitExpected = true;
  await simPage.click('#exit');
  const simExit = await poll('the sim run to exit after Exit', () => sim.child.exit);
  check(simExit.code === 0, `the sim run ended with ${describeExit(simExit)}`);
  await simContext.close();
  ok(`the real-time factor slider is disabled with real robots (factor ${mixedSlider.factor}); in ${path.basename(simScenario)} ` +
     `it set factor ${fast.rt_factor} (status; the page shows "${fast.shown}" and "${fast.state}"; events.csv "${factorLine}"), the clock ran x${ratio.toFixed(2)}; that run exited 0 by Exit`);

  // ------------------------------------------------ 5. manual driving
  await page.selectOption('#drive-robot', String(DRIVEN));
  await page.click('#drive-take');
  const driveState = await page.evaluate(() => document.getElementById('drive-state').textContent);
  check(driveState === `driving robot ${DRIVEN}`, `after Take the page says "${driveState}"`);
  const speed = Number(await page.evaluate(() => document.getElementById('drive-speed').value));
  const p0 = (await waitStill(page, DRIVEN, 'before driving')).pose;
  const drivesBefore = driveEvents(mixed.runDir, DRIVEN).length;
  await page.keyboard.down('ArrowUp');
  const heldFrom = Date.now();
  await poll('robot 4 to move forward by more than 2 cm while ArrowUp is held', async () => {
    const p = await poseOf(page, DRIVEN);
    return (p.x - p0.x) * Math.cos(p0.theta) + (p.y - p0.y) * Math.sin(p0.theta) > MOVED_M;
  }, { describe: async () => JSON.stringify(await poseOf(page, DRIVEN)) });
  const heldButton = await page.evaluate(() => document.querySelector('#drive-pad button[data-key=ArrowUp]').classList.contains('held'));
  check(heldButton, 'the ▲ button is not highlighted while ArrowUp is held');
  await screenshot(state, page, '04-driving');
  await poll('1.5 s of holding ArrowUp', () => Date.now() - heldFrom >= 1500);
  const p1 = await poseOf(page, DRIVEN);
  await page.keyboard.up('ArrowUp');
  const released = Date.now();
  const forward = (p1.x - p0.x) * Math.cos(p0.theta) + (p1.y - p0.y) * Math.sin(p0.theta);
  check(forward > MOVED_M, `robot ${DRIVEN} moved ${mm(forward)} forward in ${((released - heldFrom) / 1000).toFixed(1)} s`);
  const still = await waitStill(page, DRIVEN, 'after ArrowUp is let go');
  const stoppedIn = (Date.now() - released) / 1000;
  check(stoppedIn < STOP_WITHIN_S, `robot ${DRIVEN} stood only ${stoppedIn.toFixed(1)} s after ArrowUp was let go`);
  const [goLine, stopLine] = await driveThenStop(mixed.runDir, DRIVEN, drivesBefore, speed);
  const coasted = dist(p1, still.pose);
  ok(`manual driving: Take robot ${DRIVEN}, ArrowUp held ${((released - heldFrom) / 1000).toFixed(1)} s: ${mm(forward)} forward; ` +
     `let go: standing within ${stoppedIn.toFixed(1)} s (${mm(coasted)} after the key), events.csv "${goLine}" then "${stopLine}"`);
  await screenshot(state, page, '05-driven');

  // ------------------------------------------------ 6. closing the tab while driving
  await page.click('#drive-release');
  const releasedState = await page.evaluate(() => ({ state: document.getElementById('drive-state').textContent,
    take: document.getElementById('drive-take').disabled, release: document.getElementById('drive-release').disabled }));
  check(releasedState.state === '' && !releasedState.take && releasedState.release,
    `after Release the driving controls are ${JSON.stringify(releasedState)}`);
  await waitForEvent(mixed, `"robot ${DRIVEN} stopped and given back" (the release)`, (l) => new RegExp(`,behaviour,${DRIVEN},0,console -> `).test(l));
  const page2 = await openDrivenPage(state, context, 'page 2', mixed.url);
  await page2.selectOption('#drive-robot', String(DRIVEN));
  await page2.click('#drive-take');
  const q0 = (await waitStill(page, DRIVEN, 'before page 2 drives it')).pose;
  const drivesBefore2 = driveEvents(mixed.runDir, DRIVEN).length;
  await page2.keyboard.down('ArrowUp');
  await poll('robot 4 (seen from page 1) to move while page 2 holds ArrowUp', async () => dist(await poseOf(page, DRIVEN), q0) > 0.01,
    { describe: async () => JSON.stringify(await poseOf(page, DRIVEN)) });
  await page2.close();  // the key still down
  const closed = Date.now();
  const still2 = await waitStill(page, DRIVEN, 'after page 2 closed while driving');
  const stoppedIn2 = (Date.now() - closed) / 1000;
  check(stoppedIn2 < STOP_WITHIN_S, `robot ${DRIVEN} stood only ${stoppedIn2.toFixed(1)} s after its driver's tab closed`);
  const [goLine2, stopLine2] = await driveThenStop(mixed.runDir, DRIVEN, drivesBefore2, speed);
  ok(`closing the tab that drives robot ${DRIVEN} (page 2, ArrowUp down) stops it: page 1 sees it standing ` +
     `within ${stoppedIn2.toFixed(1)} s of the close, ${mm(dist(q0, still2.pose))} from where page 2 started it; events.csv "${goLine2}" then "${stopLine2}"`);

  // ------------------------------------------------ 7. Exit
  mixed.child.exitExpected = true;
  const dialogsBefore = state.dialogs.length;
  await page.click('#exit');
  await poll('the banner to say that the run has ended', async () => {
    const b = await banner();
    return !b.hidden && b.kind === 'ended' && /The run has ended/.test(b.text) && b;
  }, { describe: async () => JSON.stringify(await banner()) });
  check(state.dialogs.length === dialogsBefore + 1 && /End the run\?/.test(state.dialogs[dialogsBefore]),
    `Exit asked ${JSON.stringify(state.dialogs.slice(dialogsBefore))}, not one confirm "End the run?"`);
  const exit = await poll('rilbed to exit after Exit', () => mixed.child.exit);
  check(exit.code === 0, `rilbed ended with ${describeExit(exit)}, not exit code 0`);
  const lastSpeed = mixed.child.stdoutLines.find((l) => l.includes(`robot ${DRIVEN} (emulated): last speed`));
  check(lastSpeed === `robot ${DRIVEN} (emulated): last speed 0 0`, `rilbed's output says "${lastSpeed}", not "robot ${DRIVEN} (emulated): last speed 0 0"`);
  const endedLine = await waitForEvent(mixed, '"ended by gui ..."', (l) => /,console,0,0,ended by gui /.test(l));
  await poll('the page to see the server close', () => page.evaluate(() => document.getElementById('connection').textContent === 'disconnected'));
  const finalBanner = await banner();
  check(/The run has ended/.test(finalBanner.text), `once the server closed, the banner says "${finalBanner.text}"`);
  await screenshot(state, page, '06-ended');
  ok(`Exit (confirm "End the run?" accepted): banner "${finalBanner.text}", rilbed exited 0 saying "${lastSpeed}", events.csv "${endedLine}"`);

  // ------------------------------------------------ 8. robot bodies
  await checkBodies(state, binary);

  // ------------------------------------------------ no errors on any page, all along
  check(state.pageErrors.length === 0, `the pages logged ${state.pageErrors.length} errors:\n  ${state.pageErrors.join('\n  ')}`);
  ok(`no console error and no uncaught exception on any page (${state.dialogs.length} dialogs, all confirms accepted)`);
}

run(main, { name: 'browser_test', watchdogMs: WATCHDOG_MS });
