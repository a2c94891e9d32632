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

test('readScenarioText refuses what is not YAML or not a mapping, saying so', () => {
  assert.throws(() => readScenarioText('robots: [1, 2'), /^Error: not valid YAML: /);
  assert.throws(() => readScenarioText('- 1\n- 2\n'), /not a scenario \(a mapping of keys is expected\)/);
  assert.throws(() => readScenarioText('just words\n'), /not a scenario/);
});
