// Robot ID lists as rilbed reads and writes them (src/core/id_list.cpp): "1-8", "2,4,9-12",
// spaces around items allowed. The page parses them as the scenario parser does, so that
// the editor flags an `ids:` that `rilbed run` would refuse, with the same words.

// The C++ parses into an int: a number it could not hold is not an ID either.
const INT_MAX = 2147483647;
const INT_MIN = -2147483648;

const trim = (s) => s.replace(/^[ \t]+|[ \t]+$/g, '');

// A whole decimal number with an optional leading minus (std::from_chars), else null.
function parseInteger(text) {
  const s = trim(text);
  if (!/^-?\d+$/.test(s)) return null;
  const n = Number(s);
  return n >= INT_MIN && n <= INT_MAX ? n : null;
}

// One item: N or A-B (a '-' at the very start is a sign, not a range).
function parseItem(item) {
  const dash = item.indexOf('-', 1);
  const lo = parseInteger(dash < 0 ? item : item.slice(0, dash));
  const hi = dash < 0 ? lo : parseInteger(item.slice(dash + 1));
  return lo === null || hi === null || lo > hi ? null : [lo, hi];
}

// {ids, error}: the sorted, de-duplicated IDs of `text`, each in [min, max], or an error
// that quotes the offending item (ids then empty). `what` names the list in the error.
export function parseIdList(text, { min = 1, max = 100000, what = 'ID list' } = {}) {
  if (typeof text !== 'string' || trim(text) === '') return { ids: [], error: `empty ${what}` };
  const ids = new Set();
  for (const raw of text.split(',')) {
    const item = trim(raw);
    const range = parseItem(item);
    if (!range) return { ids: [], error: `bad ${what} item '${item}' (expected N or A-B with A<=B)` };
    if (range[0] < min || range[1] > max) return { ids: [], error: `${what} item '${item}' is outside ${min}..${max}` };
    for (let id = range[0]; id <= range[1]; ++id) ids.add(id);
  }
  return { ids: [...ids].sort((a, b) => a - b), error: '' };
}

// IDs as parseIdList reads them, runs of consecutive IDs as ranges: "1-4,7,9-12" (in the
// order given, as id_ranges_text writes them; empty for none).
export function idRangesText(ids) {
  const parts = [];
  for (let i = 0; i < ids.length;) {
    let last = i;
    while (last + 1 < ids.length && ids[last + 1] - ids[last] === 1) ++last;
    parts.push(last > i ? `${ids[i]}-${ids[last]}` : `${ids[i]}`);
    i = last + 1;
  }
  return parts.join(',');
}

// A robot entry's `ids:` (a list text, or one number as YAML reads `ids: 4`): its IDs, or
// null when rilbed would refuse it.
export function parseIds(value) {
  if (Number.isInteger(value)) return value >= 1 && value <= 100000 ? [value] : null;
  if (typeof value !== 'string') return null;
  const { ids, error } = parseIdList(value);
  return error ? null : ids;
}

// The IDs sorted, as ranges: what an entry's `ids:` is written as.
export const formatIds = (ids) => idRangesText([...ids].sort((a, b) => a - b));
