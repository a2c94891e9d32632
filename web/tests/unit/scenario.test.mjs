// Reading a scenario object (web/scenario.js) as rilbed run reads it.
import test from 'node:test';
import assert from 'node:assert/strict';
import {
  ROBOT_RADIUS_M, controllerRef, controllerValue, entryBody, entryIds, entryRadius, modelName, robotHasSensor, robotItems, scenarioField,
} from '../../scenario.js';

test('the field: its size, the defaults for what is missing or not above 0, its walls', () => {
  assert.deepEqual(scenarioField({ field: { width_m: 2, height_m: 1, walls: false } }), { w: 2, h: 1, walls: false });
  assert.deepEqual(scenarioField({ field: { width_m: -1 } }), { w: 1.5, h: 1.2, walls: true });
  assert.deepEqual(scenarioField({}), { w: 1.5, h: 1.2, walls: true });
});

test('an entry\'s IDs: id, or ids as a list text or a number; none when invalid', () => {
  assert.deepEqual(entryIds({ id: 3 }), [3]);
  assert.deepEqual(entryIds({ ids: '1-3,7' }), [1, 2, 3, 7]);
  assert.deepEqual(entryIds({ ids: 4 }), [4]);
  assert.deepEqual(entryIds({ id: 'x' }), []);
  assert.deepEqual(entryIds({ ids: '3-1' }), []);
  assert.deepEqual(entryIds(null), []);
});

test('robotItems: a placed robot per single entry with a pose, a tray robot per ID otherwise', () => {
  const doc = { robots: [{ id: 1, pose: [0.2, 0.3, 90] }, { ids: '2-3', pose: 'random' }, { id: 4 }] };
  const items = robotItems(doc).map(({ index, id, placed, x, y, th }) => ({ index, id, placed, x, y, th }));
  assert.deepEqual(items, [
    { index: 0, id: 1, placed: true, x: 0.2, y: 0.3, th: 90 },
    { index: 1, id: 2, placed: false, x: undefined, y: undefined, th: undefined },
    { index: 1, id: 3, placed: false, x: undefined, y: undefined, th: undefined },
    { index: 2, id: 4, placed: false, x: undefined, y: undefined, th: undefined },
  ]);
  assert.deepEqual(robotItems({ robots: 'none' }), []);
});

test('a robot without controller: runs the scenario default', () => {
  assert.deepEqual(controllerRef({}), { name: 'convoy', library: null });
  assert.deepEqual(controllerRef({ controller: null }), { name: 'convoy', library: null });
  assert.deepEqual(controllerRef({ controller: 'wander' }), { name: 'wander', library: null });
});

test('a plug-in library\'s controller, {library, name}: read with the path as the file gives it', () => {
  assert.deepEqual(controllerRef({ controller: { library: 'build/braitenberg_cpp.so', name: 'braitenberg_cpp' } }),
    { name: 'braitenberg_cpp', library: 'build/braitenberg_cpp.so' });
  // A mapping without both texts, or a list, names none (the checks say why).
  assert.equal(controllerRef({ controller: { name: 'braitenberg' } }), null);
  assert.equal(controllerRef({ controller: { library: '/x.so', name: 3 } }), null);
  assert.equal(controllerRef({ controller: {} }), null);
  assert.equal(controllerRef({ controller: ['wander'] }), null);
  assert.deepEqual(controllerRef({ controller: 42 }), { name: '42', library: null }); // (the parser reads a scalar as text)
});

test('controllerValue: rilbed\'s own by name, a library\'s as {library, name}, the library first as in the examples', () => {
  assert.equal(controllerValue({ name: 'wander', library: null }), 'wander');
  const v = controllerValue({ name: 'braitenberg_cpp', library: '/abs/braitenberg_cpp.so', params: [] });
  assert.deepEqual(v, { library: '/abs/braitenberg_cpp.so', name: 'braitenberg_cpp' });
  assert.deepEqual(Object.keys(v), ['library', 'name']);
});

test('robotHasSensor as robot_has_sensor: defaults on, lists need an element, the pose always', () => {
  assert.equal(robotHasSensor(undefined, 'proximity'), true);
  assert.equal(robotHasSensor({ proximity: false }, 'proximity'), false);
  assert.equal(robotHasSensor({ proximity: { range_m: 0.05 } }, 'proximity'), true);
  assert.equal(robotHasSensor({}, 'odometer'), true);
  assert.equal(robotHasSensor({ odometer: false }, 'odometer'), false);
  assert.equal(robotHasSensor({ odometer: false, proximity: false }, 'pose'), true);
  assert.equal(robotHasSensor({}, 'track'), false);
  assert.equal(robotHasSensor({ track: [] }, 'track'), false);
  assert.equal(robotHasSensor({ track: [{ height_mm: 8 }] }, 'track'), true);
  assert.equal(robotHasSensor({ range_finders: [{}] }, 'range_finders'), true);
  assert.equal(robotHasSensor({}, 'beacon_finder'), false);
  assert.equal(robotHasSensor({ beacon_finder: { field_of_view_deg: 360 } }, 'beacon_finder'), true);
});

test('entryBody: a body override as drawn (its wheels, else the Khepera\'s); none without one, or one that cannot be drawn', () => {
  assert.equal(entryBody({ id: 1 }), null);
  assert.equal(entryBody({ id: 1, model: 'epuck' }), null); // the model file's: the page does not read it
  assert.equal(entryBody({ id: 1, wheels: { base_m: 0.06 } }), null);
  assert.equal(entryBody({ id: 1, body: { outline_m: [[0.03, 0], [-0.03, 0]] } }), null);
  assert.equal(entryBody({ id: 1, body: [0.05] }), null);
  assert.deepEqual(entryBody({ body: { radius_m: 0.05 }, wheels: { base_m: 0.07 } }),
    { name: 'khepera2', radius_m: 0.05, outline: [], wheel_base_m: 0.07, wheel_radius_m: 0.00764 });
  const square = entryBody({ model: 'square', body: { outline_m: [[0.035, 0.035], [-0.035, 0.035], [-0.035, -0.035], [0.035, -0.035]] } });
  assert.deepEqual(square.outline, [[0.035, 0.035], [-0.035, 0.035], [-0.035, -0.035], [0.035, -0.035]]);
  assert.ok(Math.abs(square.radius_m - Math.hypot(0.035, 0.035)) < 1e-15);
  assert.equal(entryRadius({ body: { radius_m: 0.05 } }), 0.05);
  assert.equal(entryRadius({ model: 'epuck' }), ROBOT_RADIUS_M);
});

test('modelName: the model file\'s name without its folder and .yaml', () => {
  assert.equal(modelName({ model: 'epuck' }), 'epuck');
  assert.equal(modelName({ model: 'robots/epuck.yaml' }), 'epuck');
  assert.equal(modelName({ model: '../lab/wedge_bot.yml' }), 'wedge_bot');
  assert.equal(modelName({ model: '' }), null);
  assert.equal(modelName({ id: 1 }), null);
  assert.equal(modelName({ model: 3 }), null);
});
