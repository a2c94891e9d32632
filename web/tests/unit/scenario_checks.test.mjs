// The scenario checks (web/scenario_checks.js): what rilbed run would refuse, the robots'
// controllers, parameters and sensors checked against the registry alone.
import test from 'node:test';
import assert from 'node:assert/strict';
import { parseRegistry } from '../../controller_registry.js';
import { bodyProblems, controllerProblems, findProblems, paramsProblems } from '../../scenario_checks.js';
import { C_LIBRARY, CPP_LIBRARY, LIBRARY_REGISTRY_JSON, REGISTRY_JSON } from './registry_fixture.mjs';

const registry = parseRegistry(JSON.parse(JSON.stringify(REGISTRY_JSON)));
const sweeper = registry.find('sweeper');
const sweeperSensors = { range_finders: [{ mount_deg: 0 }], track: [{ height_mm: 8 }] };
const scenario = (robots, more = {}) => ({ field: { width_m: 1.5, height_m: 1.2 }, robots, ...more });

test('a good scenario has no problem', () => {
  const doc = scenario([
    { ids: '1-2', pose: 'random' },
    { id: 3, pose: [0.5, 0.5, 0], controller: 'wander', params: { speed_mps: 0.2 } },
    { id: 4, pose: [0.8, 0.5, 0], controller: 'sweeper', params: { lanes: 3 }, sensors: sweeperSensors },
  ]);
  assert.deepEqual(findProblems(doc, registry), []);
});

test('a controller the registry does not have is unknown, named with those it has', () => {
  assert.deepEqual(controllerProblems({ controller: 'track_follow' }, registry),
    ["unknown controller 'track_follow' (rilbed knows convoy, wander, sweeper)"]);
  const doc = scenario([{ id: 1, pose: 'random', controller: 'beacon_homing' }]);
  assert.deepEqual(findProblems(doc, registry), ["robots[0]: unknown controller 'beacon_homing' (rilbed knows convoy, wander, sweeper)."]);
});

test('a Python class is the run\'s to check; only the shape of its mapping is the page\'s', () => {
  assert.deepEqual(controllerProblems({ controller: { python: '../examples/python/convoy.py', class: 'Convoy' }, params: { standoff_m: 0.1 } }, registry), []);
  assert.deepEqual(controllerProblems({ controller: { python: 'convoy.py', klass: 'Convoy' } }, registry), [
    'controller.klass: unknown key (allowed here: python, class)',
    'controller.class: give the name of a class of the file that subclasses rilbed.Controller',
  ]);
  assert.deepEqual(controllerProblems({ controller: { python: '', class: 'Convoy' } }, registry),
    ["controller.python: give the Python file's path, relative to the scenario file"]);
});

test('a parameter the controller does not take', () => {
  assert.deepEqual(paramsProblems(registry.find('wander'), { speed_mps: 0.1, lanes: 2 }),
    ["controller wander has no parameter 'lanes' (it takes speed_mps)"]);
  assert.deepEqual(paramsProblems(registry.find('convoy'), { speed_mps: 0.1 }),
    ["controller convoy has no parameter 'speed_mps' (it takes none)"]);
});

test('values out of range, not whole, not numbers', () => {
  const wander = registry.find('wander');
  assert.deepEqual(paramsProblems(wander, { speed_mps: 5 }), ['params.speed_mps must be 0 to 1.016 (m/s), not 5']);
  assert.deepEqual(paramsProblems(wander, { speed_mps: -0.01 }), ['params.speed_mps must be 0 to 1.016 (m/s), not -0.01']);
  assert.deepEqual(paramsProblems(wander, { speed_mps: 1.016 }), []);
  assert.deepEqual(paramsProblems(wander, { speed_mps: 'fast' }), ['params.speed_mps must be a number, not "fast"']);
  assert.deepEqual(paramsProblems(sweeper, { lanes: 2.5 }), ['params.lanes must be a whole number, not 2.5']);
  assert.deepEqual(paramsProblems(sweeper, { lanes: 21 }), ['params.lanes must be 1 to 20, not 21']);
  assert.deepEqual(paramsProblems(sweeper, { lanes: 2, gap_m: 0.001 }), ['params.gap_m must be at least 0.01 (m), not 0.001']);
  assert.deepEqual(paramsProblems(sweeper, { lanes: 2, gap_m: 50, bias: -1e9 }), []);
  assert.deepEqual(paramsProblems(wander, [0.1]), ['params must be a mapping of names to numbers ({speed_mps: 0.08})']);
});

test('a required parameter missing', () => {
  assert.deepEqual(paramsProblems(sweeper, {}), ["controller sweeper needs parameter 'lanes' (how many lanes)"]);
  assert.deepEqual(paramsProblems(sweeper, undefined), ["controller sweeper needs parameter 'lanes' (how many lanes)"]);
});

test('a required sensor missing, each named', () => {
  assert.deepEqual(controllerProblems({ controller: 'sweeper', params: { lanes: 1 } }, registry),
    ['sweeper needs sensors: range_finders', 'sweeper needs sensors: track']);
  assert.deepEqual(controllerProblems({ controller: 'sweeper', params: { lanes: 1 }, sensors: { track: [{}], range_finders: [] } }, registry),
    ['sweeper needs sensors: range_finders']);
});

test('every problem of an entry is prefixed with the entry', () => {
  const doc = scenario([{ id: 1, pose: 'random' }, { ids: '2-3', controller: 'wander', params: { speed_mps: 2 } }]);
  assert.deepEqual(findProblems(doc, registry), ['robots[1]: params.speed_mps must be 0 to 1.016 (m/s), not 2.']);
});

test('without a registry the controllers go unchecked, the rest is still checked', () => {
  const doc = scenario([{ id: 1, pose: 'random', controller: 'nonsense', params: { x: 'y' } }, { id: 1, pose: 'random' }]);
  assert.deepEqual(findProblems(doc, null), ['robot 1 is defined twice.']);
});

test('robots: at least one, IDs valid and once, a real one with a link and a camera', () => {
  assert.deepEqual(findProblems(scenario([]), registry), ['robots: rilbed run needs at least one robot.']);
  assert.deepEqual(findProblems(scenario([{ ids: '0-2' }, { id: 1 }]), registry), ['robots[0]: no valid id or ids.']);
  assert.deepEqual(findProblems(scenario([{ id: 1, kind: 'real' }]), registry),
    ['robots[0]: a real robot needs a link.', 'camera: real robots need a camera.']);
  assert.deepEqual(findProblems(scenario([{ id: 1, kind: 'real', link: { emulate: true } }], { camera: { emulate: true } }), registry), []);
});

test('convoy robots numbered 1..N', () => {
  const doc = scenario([{ ids: '1-2' }, { id: 4 }, { id: 3, controller: 'wander' }]);
  assert.deepEqual(findProblems(doc, registry), ['convoy robots must be numbered 1..N; they are 1-2,4.']);
});

test('placed robots against the walls, the obstacles and each other', () => {
  const obstacles = [{ name: 'box', polygon: [[0.4, 0.4], [0.6, 0.4], [0.6, 0.6], [0.4, 0.6]] }];
  const doc = scenario([
    { id: 1, pose: [0.01, 0.5, 0] },
    { id: 2, pose: [0.5, 0.5, 0] },
    { id: 3, pose: [0.62, 0.5, 0] },
    { id: 4, pose: [1.0, 1.0, 0] },
    { id: 5, pose: [1.04, 1.0, 0] },
  ], { obstacles });
  assert.deepEqual(findProblems(doc, registry), [
    'robot 1 overlaps a wall.', 'robot 2 is inside obstacle 1 (box).', 'robot 3 overlaps obstacle 1 (box).', 'robots 4 and 5 overlap.',
  ]);
  const open = scenario([{ id: 1, pose: [0.01, 0.5, 0] }], { field: { width_m: 1.5, height_m: 1.2, walls: false } });
  assert.deepEqual(findProblems(open, registry), []);
});

// ---------------------------------------------------------------- bodies
const SQUARE = [[0.035, 0.035], [-0.035, 0.035], [-0.035, -0.035], [0.035, -0.035]]; // robots/square.yaml's
const WEDGE = [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]]; // examples/robots/wedge_bot's

test('model, body and wheels are a robot entry\'s keys: no problem when they are right', () => {
  const doc = scenario([
    { ids: '1-2', model: 'epuck', pose: 'random' },
    { id: 3, model: 'robots/square.yaml', pose: [0.3, 0.3, 30], wheels: { base_m: 0.058 } },
    { id: 4, model: 'epuck', body: { outline_m: WEDGE }, wheels: { base_m: 0.05, radius_m: 0.012 }, pose: [0.6, 0.3, 0] },
    { id: 5, body: { radius_m: 0.05 }, pose: [0.9, 0.3, 0] },
    { id: 6, body: { outline_m: [...SQUARE].reverse() }, pose: [1.2, 0.3, 90] }, // clockwise: the run turns it round
  ]);
  assert.deepEqual(findProblems(doc, registry), []);
  assert.deepEqual(bodyProblems({ model: 'khepera2', body: { outline_m: SQUARE }, wheels: { base_m: 0.06, radius_m: 0.016 } }), []);
});

test('an outline needs at least 3 points, each [x, y]; at most 32', () => {
  assert.deepEqual(bodyProblems({ body: { outline_m: [[0.03, 0], [-0.03, 0]] } }), ['body.outline_m needs at least 3 points, not 2']);
  assert.deepEqual(bodyProblems({ body: { outline_m: [] } }), ['body.outline_m needs at least 3 points, not 0']);
  assert.deepEqual(bodyProblems({ body: { outline_m: [[0.03, 0], [0, 0.03, 1], [-0.03, 0]] } }), ['body.outline_m: point 2 is not [x, y] (metres)']);
  assert.deepEqual(bodyProblems({ body: { outline_m: 'square' } }), ['body.outline_m must be a list of [x, y] points (robot frame: x forward, y left, metres)']);
  const many = Array.from({ length: 33 }, (_, k) => [0.03 * Math.cos((2 * Math.PI * k) / 33), 0.03 * Math.sin((2 * Math.PI * k) / 33)]);
  assert.deepEqual(bodyProblems({ body: { outline_m: many } }), ['body.outline_m has 33 points: at most 32']);
  assert.deepEqual(bodyProblems({ body: { outline_m: many.slice(0, 32) } }), []);
  const doc = scenario([{ id: 1, pose: [0.5, 0.5, 0], body: { outline_m: [[0.03, 0], [-0.03, 0.02]] } }]);
  assert.deepEqual(findProblems(doc, registry), ['robots[0]: body.outline_m needs at least 3 points, not 2.']);
});

test('an outline as the run checks it: convex, not crossing itself, with an area, around the centre', () => {
  const notch = [[0.04, 0.04], [-0.04, 0.04], [-0.01, 0], [-0.04, -0.04], [0.04, -0.04]];
  assert.deepEqual(bodyProblems({ body: { outline_m: notch } }), ['body.outline_m is not convex']);
  const star = [0, 2, 4, 1, 3].map((k) => [0.04 * Math.cos((2 * Math.PI * k) / 5), 0.04 * Math.sin((2 * Math.PI * k) / 5)]);
  assert.deepEqual(bodyProblems({ body: { outline_m: star } }), ['body.outline_m crosses itself']);
  assert.deepEqual(bodyProblems({ body: { outline_m: [[0.03, 0], [0, 0], [-0.03, 0]] } }), ['body.outline_m has (almost) no area']);
  assert.deepEqual(bodyProblems({ body: { outline_m: [[0.01, -0.02], [0.05, -0.02], [0.05, 0.02], [0.01, 0.02]] } }),
    ["body.outline_m must hold the robot's centre (0, 0) strictly inside"]);
  assert.deepEqual(bodyProblems({ body: { outline_m: [[2, 0], [-0.1, 0.1], [-0.1, -0.1]] } }),
    ["body.outline_m reaches more than 1 m from the centre (a robot on a lab's table)"]);
});

test('body and wheels: their keys, one shape, numbers above 0; model a name', () => {
  assert.deepEqual(bodyProblems({ body: { radius_m: 0.03, outline_m: SQUARE } }), ['body: give either radius_m (a disc) or outline_m']);
  assert.deepEqual(bodyProblems({ body: { radius_m: 0, height_m: 0.02 } }),
    ['body.height_m: unknown key (allowed here: radius_m, outline_m)', 'body.radius_m must be a number above 0, not 0']);
  assert.deepEqual(bodyProblems({ body: { radius_m: 1.5 } }), ["body.radius_m is at most 1 m (a robot on a lab's table)"]);
  assert.deepEqual(bodyProblems({ body: 0.03 }), ['body must be {radius_m: R} (a disc) or {outline_m: [[x, y], ...]} (a convex outline, robot frame)']);
  assert.deepEqual(bodyProblems({ wheels: { base_m: -1, radius_m: 'big', width_m: 0.01 } }), [
    'wheels.width_m: unknown key (allowed here: base_m, radius_m)', 'wheels.base_m must be a number above 0, not -1',
    'wheels.radius_m must be a number above 0, not "big"',
  ]);
  assert.deepEqual(bodyProblems({ wheels: { base_m: 3, radius_m: 0.6 } }), ['wheels.base_m is at most 2 m', 'wheels.radius_m is at most 0.5 m']);
  assert.deepEqual(bodyProblems({ wheels: [0.05, 0.01] }), ['wheels must be {base_m: B, radius_m: R}']);
  assert.deepEqual(bodyProblems({ model: '' }), ["model must name a robot model file (robots/epuck.yaml) or a shipped model's name (epuck)"]);
  assert.deepEqual(bodyProblems({ model: 3 }), ["model must name a robot model file (robots/epuck.yaml) or a shipped model's name (epuck)"]);
});

test('placed robots overlap by their body overrides: discs by their radius, outlines by their shape', () => {
  // 40 mm from the left wall: a disc of 50 mm overlaps it, a Khepera (27.5 mm) does not.
  assert.deepEqual(findProblems(scenario([{ id: 1, pose: [0.04, 0.5, 0], body: { radius_m: 0.05 } }]), registry), ['robot 1 overlaps a wall.']);
  assert.deepEqual(findProblems(scenario([{ id: 1, pose: [0.04, 0.5, 0] }]), registry), []);
  // A square 40 mm from the wall: it fits facing +x (its side 35 mm out), not turned 45 degrees (its corner 49.5 mm out).
  assert.deepEqual(findProblems(scenario([{ id: 1, pose: [0.04, 0.5, 0], body: { outline_m: SQUARE } }]), registry), []);
  assert.deepEqual(findProblems(scenario([{ id: 1, pose: [0.04, 0.5, 45], body: { outline_m: SQUARE } }]), registry), ['robot 1 overlaps a wall.']);
  // Two squares side by side 72 mm apart fit; turned 45 degrees their corners meet.
  const two = (th) => scenario([{ id: 1, pose: [0.5, 0.5, th], body: { outline_m: SQUARE } }, { id: 2, pose: [0.572, 0.5, th], body: { outline_m: SQUARE } }]);
  assert.deepEqual(findProblems(two(0), registry), []);
  assert.deepEqual(findProblems(two(45), registry), ['robots 1 and 2 overlap.']);
  // A square and a Khepera: 65 mm apart they are clear along the square's side, not towards its corner.
  const squareAndDisc = (th) => scenario([{ id: 1, pose: [0.5, 0.5, th], body: { outline_m: SQUARE } }, { id: 2, pose: [0.565, 0.5, 0] }]);
  assert.deepEqual(findProblems(squareAndDisc(0), registry), []);
  assert.deepEqual(findProblems(squareAndDisc(45), registry), ['robots 1 and 2 overlap.']);
  // Against an obstacle: the wedge's nose reaches it facing it, not facing away.
  const obstacles = [{ name: 'box', polygon: [[0.55, 0.4], [0.7, 0.4], [0.7, 0.6], [0.55, 0.6]] }];
  const wedge = (th) => scenario([{ id: 1, pose: [0.5, 0.5, th], body: { outline_m: WEDGE } }], { obstacles });
  assert.deepEqual(findProblems(wedge(0), registry), ['robot 1 overlaps obstacle 1 (box).']);
  assert.deepEqual(findProblems(wedge(180), registry), []);
  // A model alone is the model file's body, which the page does not read: checked as a Khepera.
  assert.deepEqual(findProblems(scenario([{ id: 1, pose: [0.04, 0.5, 0], model: 'epuck' }]), registry), []);
});

test('obstacles, tracks and beacons', () => {
  const doc = scenario([{ id: 1 }], {
    obstacles: [{ polygon: [[0, 0], [1, 0]] }],
    tracks: [{ points: [[0, 0]] }],
    beacons: [{ id: 1, aperture_deg: 400 }, { id: 1, range_m: 0 }],
  });
  assert.deepEqual(findProblems(doc, registry), [
    'obstacle 1 needs at least 3 points.', 'track 1 needs at least 2 points.', 'beacon 1: aperture_deg must be in (0, 360].',
    'beacon 1 is defined twice.', 'beacon 2: range_m must be above 0.',
  ]);
});

// ---------------------------------------------------------------- plug-in libraries
// A run's registry with two libraries' controllers, which a scenario names {library, name}.
const withLibraries = parseRegistry(JSON.parse(JSON.stringify(LIBRARY_REGISTRY_JSON)));
const cpp = (library = CPP_LIBRARY, name = 'braitenberg_cpp') => ({ library, name });

test('library controllers, by absolute path or relative to the file, with their params: no problem', () => {
  const doc = scenario([
    { ids: '1-2', pose: 'random' },
    { id: 3, pose: [0.5, 0.5, 0], controller: cpp(), params: { gain: 2, speed_mps: 0.1 } },
    { id: 4, pose: [0.8, 0.5, 0], controller: cpp('build/braitenberg_cpp.so'), params: { gain: 0 } },
    { ids: '5-6', controller: { library: '../../build/plugins/braitenberg.so', name: 'braitenberg' } },
    { id: 7, controller: 'wander' },
  ]);
  assert.deepEqual(findProblems(doc, withLibraries), []);
});

test('a library controller\'s params and sensors are checked against its own registry entry', () => {
  assert.deepEqual(controllerProblems({ controller: cpp() }, withLibraries), ["controller braitenberg_cpp needs parameter 'gain' (how hard it turns away)"]);
  assert.deepEqual(controllerProblems({ controller: cpp(), params: { gain: 11, lanes: 2 } }, withLibraries), [
    'params.gain must be 0 to 10, not 11', "controller braitenberg_cpp has no parameter 'lanes' (it takes gain, speed_mps)",
  ]);
  assert.deepEqual(controllerProblems({ controller: cpp(), params: { gain: 1 }, sensors: { proximity: false } }, withLibraries),
    ['braitenberg_cpp needs sensors: proximity']);
});

test('a library controller the registry does not have is unknown, named with its library and what that holds', () => {
  assert.deepEqual(controllerProblems({ controller: cpp(CPP_LIBRARY, 'braitenberg') }, withLibraries),
    [`unknown controller 'braitenberg' of plug-in library ${CPP_LIBRARY} (it holds braitenberg_cpp)`]);
  assert.deepEqual(controllerProblems({ controller: cpp('/elsewhere/braitenberg_cpp.so') }, withLibraries),
    [`unknown controller 'braitenberg_cpp' of plug-in library /elsewhere/braitenberg_cpp.so (the registry has none of its controllers; its plug-in libraries: ${CPP_LIBRARY}, ${C_LIBRARY})`]);
  assert.deepEqual(controllerProblems({ controller: cpp('plugins/braitenberg_cpp.so') }, withLibraries),
    [`unknown controller 'braitenberg_cpp' of plug-in library plugins/braitenberg_cpp.so (the registry has none of its controllers; its plug-in libraries: ${CPP_LIBRARY}, ${C_LIBRARY})`]);
  // A library does not name a built-in, and a registry without libraries says so.
  assert.deepEqual(controllerProblems({ controller: cpp(CPP_LIBRARY, 'wander') }, withLibraries),
    [`unknown controller 'wander' of plug-in library ${CPP_LIBRARY} (it holds braitenberg_cpp)`]);
  const doc = scenario([{ id: 1, pose: 'random', controller: cpp() }]);
  assert.deepEqual(findProblems(doc, registry),
    [`robots[0]: unknown controller 'braitenberg_cpp' of plug-in library ${CPP_LIBRARY} (the registry has no plug-in library).`]);
});

test('a library controller named by its name alone is refused as the parser does, and unknown names list library ones', () => {
  assert.deepEqual(controllerProblems({ controller: 'braitenberg_cpp', params: { gain: 1 } }, withLibraries),
    [`'braitenberg_cpp' comes from the plug-in library ${CPP_LIBRARY}: name it as {library: PATH, name: braitenberg_cpp}`]);
  assert.deepEqual(controllerProblems({ controller: 'track_follow' }, withLibraries),
    ["unknown controller 'track_follow' (rilbed knows convoy, wander, sweeper, braitenberg_cpp (braitenberg_cpp.so), braitenberg (braitenberg.so))"]);
});

test('a controller mapping needs a library and a name, and takes nothing else; a list names nothing', () => {
  assert.deepEqual(controllerProblems({ controller: { name: 'braitenberg_cpp' } }, withLibraries),
    ["controller.library: give the plug-in library's path, relative to the scenario file"]);
  assert.deepEqual(controllerProblems({ controller: { library: CPP_LIBRARY, name: '' } }, withLibraries),
    ["controller.name: give the name of one of the library's controllers"]);
  assert.deepEqual(controllerProblems({ controller: { ...cpp(), params: { gain: 1 } } }, withLibraries),
    ['controller.params: unknown key (allowed here: library, name)']);
  assert.deepEqual(controllerProblems({ controller: ['wander'] }, withLibraries),
    ["controller must be a controller's name or {library: PATH, name: NAME}"]);
});

test('a library controller is no convoy robot, whatever its IDs', () => {
  const doc = scenario([{ ids: '1-2' }, { ids: '5-6', controller: cpp(C_LIBRARY, 'braitenberg') }]);
  assert.deepEqual(findProblems(doc, withLibraries), []);
});
