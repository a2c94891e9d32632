// A scenario's YAML text read and written as the editor does (web/scenario_yaml.js, with
// web/node_modules' js-yaml): library controllers read as {library, name} and matched to
// the registry, written back as such, a built-in's as its name.
import test from 'node:test';
import assert from 'node:assert/strict';
import { parseRegistry } from '../../controller_registry.js';
import { controllerRef, controllerValue } from '../../scenario.js';
import { findProblems } from '../../scenario_checks.js';
import { readScenarioText, scenarioText } from '../../scenario_yaml.js';
import { CPP_LIBRARY, LIBRARY_REGISTRY_JSON } from './registry_fixture.mjs';

const registry = parseRegistry(JSON.parse(JSON.stringify(LIBRARY_REGISTRY_JSON)));

// As examples/controllers/braitenberg_cpp/arena.yaml names its library (relative to the
// file), with a built-in beside it; in the editor's style, so that it is saved unchanged.
const ARENA = `# Robots of a plug-in library and one of rilbed's own.
#   rilbed run arena.yaml
name: arena
field: {width_m: 1.2, height_m: 1}
duration_s: 30
robots:
  - ids: 1-4
    pose: random
    controller: {library: build/braitenberg_cpp.so, name: braitenberg_cpp}
    params: {gain: 2}
  - id: 5
    pose: [0.6, 0.5, 90]
    controller: wander
`;

test('reading: a library controller is a {library, name} mapping, matched to its registry entry', () => {
  const { doc, header } = readScenarioText(ARENA);
  assert.equal(header, "# Robots of a plug-in library and one of rilbed's own.\n#   rilbed run arena.yaml\n");
  assert.deepEqual(doc.robots[0].controller, { library: 'build/braitenberg_cpp.so', name: 'braitenberg_cpp' });
  const c = registry.match(controllerRef(doc.robots[0]));
  assert.equal(c.name, 'braitenberg_cpp');
  assert.equal(c.library, CPP_LIBRARY);
  assert.deepEqual(c.params.map((p) => p.name), ['gain', 'speed_mps']);
  assert.equal(registry.match(controllerRef(doc.robots[1])).name, 'wander');
  assert.deepEqual(findProblems(doc, registry), []);
});

test('round trip: a scenario with a library controller is saved as it was read, the mapping and its path kept', () => {
  const { doc, header } = readScenarioText(ARENA);
  assert.equal(scenarioText(doc, header), ARENA);
});

test('writing: a library controller as {library: PATH, name: NAME} with the registry\'s path, a built-in by name', () => {
  const { doc } = readScenarioText(ARENA);
  doc.robots[1].controller = controllerValue(registry.find('braitenberg'));
  doc.robots.push({ id: 6, pose: [0.3, 0.3, 0], controller: controllerValue(registry.find('wander')) });
  const text = scenarioText(doc);
  assert.match(text, /^ {4}controller: \{library: \/home\/me\/rilbed\/build\/plugins\/braitenberg\.so, name: braitenberg\}$/m);
  assert.match(text, /^ {2}- id: 6\n {4}pose: \[0\.3, 0\.3, 0\]\n {4}controller: wander\n/m);
  const back = readScenarioText(text).doc;
  assert.deepEqual(back, JSON.parse(JSON.stringify(doc)));
  assert.equal(registry.match(controllerRef(back.robots[1])).name, 'braitenberg');
});

test('writing: a library path the flow style cannot hold plainly is quoted, and reads back the same', () => {
  const doc = { name: 'odd', robots: [{ id: 1, controller: { library: '/home/me/my libs: v2/b.so', name: 'b' } }] };
  assert.deepEqual(readScenarioText(scenarioText(doc)).doc, doc);
});

// Robots of parts (robots/*.yaml named by model:, with body and wheels overrides), in the
// editor's style: saved as read, every key of every entry kept.
const BODIES = `# Robot models and overrides.
name: bodies
field: {width_m: 1.2, height_m: 1}
duration_s: 30
robots:
  - ids: 1-2
    model: epuck
    controller: wander
  - id: 3
    model: robots/square.yaml
    pose: [0.3, 0.3, 30]
    controller: wander
    wheels: {base_m: 0.058}
  - id: 4
    model: epuck
    body: {outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]]}
    wheels: {base_m: 0.064, radius_m: 0.018}
    pose: [0.6, 0.5, 90]
    controller: wander
  - id: 5
    body: {radius_m: 0.05}
    pose: [0.9, 0.5, 0]
    controller: wander
`;

test('round trip: model, body and wheels of robot entries are saved as they were read', () => {
  const { doc, header } = readScenarioText(BODIES);
  assert.equal(doc.robots[1].model, 'robots/square.yaml');
  assert.deepEqual(doc.robots[2].body, { outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]] });
  assert.deepEqual(doc.robots[2].wheels, { base_m: 0.064, radius_m: 0.018 });
  assert.deepEqual(doc.robots[3].body, { radius_m: 0.05 });
  assert.equal(scenarioText(doc, header), BODIES);
  assert.deepEqual(findProblems(doc, registry), []);
});

test('round trip: an outline written in block style reads back the same, written in flow style', () => {
  const block = BODIES.replace('    body: {outline_m: [[0.065, 0], [-0.025, 0.035], [-0.025, -0.035]]}\n',
    '    body:\n      outline_m:\n        - [0.065, 0]\n        - [-0.025, 0.035]\n        - [-0.025, -0.035]\n');
  assert.notEqual(block, BODIES);
  const { doc, header } = readScenarioText(block);
  assert.equal(scenarioText(doc, header), BODIES);
  // A long outline (16 points) still reads back the same.
  const round6 = (v) => Math.round(v * 1e6) / 1e6 + 0; // (+ 0: never -0, which JSON makes 0)
  doc.robots[2].body.outline_m = Array.from({ length: 16 }, (_, k) => [0.041234 * Math.cos((k * Math.PI) / 8), 0.041234 * Math.sin((k * Math.PI) / 8)].map(round6));
  assert.deepEqual(readScenarioText(scenarioText(doc)).doc, JSON.parse(JSON.stringify(doc)));
});

test('readScenarioText refuses what is not YAML or not a mapping, saying so', () => {
  assert.throws(() => readScenarioText('robots: [1, 2'), /^Error: not valid YAML: /);
  assert.throws(() => readScenarioText('- 1\n- 2\n'), /not a scenario \(a mapping of keys is expected\)/);
  assert.throws(() => readScenarioText('just words\n'), /not a scenario/);
});
