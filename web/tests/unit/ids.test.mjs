// Robot ID lists (web/ids.js) read and written as src/core/id_list.cpp does.
import test from 'node:test';
import assert from 'node:assert/strict';
import { formatIds, idRangesText, parseIdList, parseIds } from '../../ids.js';

test('parseIdList reads single IDs, ranges and mixes, sorted and de-duplicated', () => {
  assert.deepEqual(parseIdList('1-8'), { ids: [1, 2, 3, 4, 5, 6, 7, 8], error: '' });
  assert.deepEqual(parseIdList('1,3,5-7').ids, [1, 3, 5, 6, 7]);
  assert.deepEqual(parseIdList('9-12, 2 ,4').ids, [2, 4, 9, 10, 11, 12]);
  assert.deepEqual(parseIdList('3,1-4,3').ids, [1, 2, 3, 4]);
  assert.deepEqual(parseIdList(' 5 - 6 ').ids, [5, 6]);
  assert.deepEqual(parseIdList('7').ids, [7]);
  assert.deepEqual(parseIdList('007').ids, [7]);
});

test('parseIdList refuses what parse_id_list refuses, quoting the item', () => {
  assert.equal(parseIdList('').error, 'empty ID list');
  assert.equal(parseIdList('  ').error, 'empty ID list');
  assert.equal(parseIdList('5-3').error, "bad ID list item '5-3' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('1,,2').error, "bad ID list item '' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('1,').error, "bad ID list item '' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('1-').error, "bad ID list item '1-' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('a').error, "bad ID list item 'a' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('1.5').error, "bad ID list item '1.5' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('+3').error, "bad ID list item '+3' (expected N or A-B with A<=B)");
  assert.equal(parseIdList('99999999999').error, "bad ID list item '99999999999' (expected N or A-B with A<=B)");
  assert.deepEqual(parseIdList('5-3').ids, []);
});

test('parseIdList keeps IDs within min..max, a leading minus being a sign', () => {
  assert.equal(parseIdList('0-3').error, "ID list item '0-3' is outside 1..100000");
  assert.equal(parseIdList('-3').error, "ID list item '-3' is outside 1..100000");
  assert.equal(parseIdList('100001').error, "ID list item '100001' is outside 1..100000");
  assert.deepEqual(parseIdList('-2-1', { min: -5, max: 5 }).ids, [-2, -1, 0, 1]);
  assert.equal(parseIdList('1-9', { min: 1, max: 8, what: 'list' }).error, "list item '1-9' is outside 1..8");
});

test('idRangesText writes runs as ranges, in the order given', () => {
  assert.equal(idRangesText([1, 2, 3, 4, 7, 9, 10, 11, 12]), '1-4,7,9-12');
  assert.equal(idRangesText([5]), '5');
  assert.equal(idRangesText([]), '');
  assert.equal(idRangesText([3, 2, 1]), '3,2,1');
  assert.equal(idRangesText([1, 3]), '1,3');
});

test('formatIds sorts first; what it writes reads back the same', () => {
  assert.equal(formatIds([7, 1, 2, 3, 5]), '1-3,5,7');
  for (const ids of [[1], [1, 2], [2, 4, 9, 10, 11], [100, 1, 50, 51]]) {
    assert.deepEqual(parseIdList(formatIds(ids)).ids, [...ids].sort((a, b) => a - b));
  }
});

test('parseIds takes an entry\'s ids: a list text or one number, null when refused', () => {
  assert.deepEqual(parseIds('4-5'), [4, 5]);
  assert.deepEqual(parseIds(4), [4]);
  assert.equal(parseIds(0), null);
  assert.equal(parseIds(2.5), null);
  assert.equal(parseIds('4-'), null);
  assert.equal(parseIds(undefined), null);
  assert.equal(parseIds(['1', '2']), null);
});
