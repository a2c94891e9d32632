// A scenario object to and from its YAML text (scenarios/README.md), as the editor loads
// and saves it: DOM-free, so that Node's unit tests can read and write scenarios as the
// page does. It needs web/node_modules (js-yaml, which ./run installs), as the page does.
import { load, dump, visit, COLLECTION_STYLE, VISIT_SKIP } from './node_modules/js-yaml/dist/js-yaml.mjs';

// The scenario object of YAML text `text`, and the file's leading comment lines (what it
// is, how to run it), which saving keeps: {doc, header}. Throws, saying why, when the text
// is not YAML or not a mapping of keys.
export function readScenarioText(text) {
  let doc;
  try {
    doc = load(text);
  } catch (e) {
    throw new Error(`not valid YAML: ${String(e.message).split('\n')[0]}`, { cause: e });
  }
  if (!doc || typeof doc !== 'object' || Array.isArray(doc)) throw new Error('not a scenario (a mapping of keys is expected)');
  const header = (/^(?:[ \t]*#[^\n]*\n|[ \t]*\n)*/.exec(text)[0] || '').replace(/\s*$/, '');
  return { doc, header: header ? `${header}\n` : '' };
}

// Short collections in flow style (`[0.3, 0.3]`, `{width_m: 1.5, height_m: 1.2}`,
// `{library: build/braitenberg.so, name: braitenberg}`), as the shipped scenarios are
// written; lists of points always on one line.
function flowLength(n) {
  if (n.kind === 'scalar') return n.value.length + (/[\s:,[\]{}#'"]|^$/.test(n.value) ? 2 : 0);
  if (n.kind === 'sequence') return 2 + n.items.reduce((a, it) => a + flowLength(it) + 2, 0);
  if (n.kind === 'mapping') return 2 + n.items.reduce((a, it) => a + flowLength(it.key) + 2 + flowLength(it.value) + 2, 0);
  return 10;
}
const scalarsOnly = (n) => n.kind === 'scalar' || (n.kind === 'sequence' && n.items.every((i) => i.kind === 'scalar'));
const FLOW_WIDTH = 120;
function toYaml(doc) {
  const block = new WeakSet(); // the items of a list whose items do not all fit a line each
  const fits = (node, depth) => flowLength(node) + 2 * depth + 24 <= FLOW_WIDTH;
  return dump(doc, {
    lineWidth: -1, noRefs: true,
    transform: (docs) => visit(docs, (node, c) => {
      if ((node.kind !== 'sequence' && node.kind !== 'mapping') || c.depth === 0 || block.has(node)) return undefined;
      const points = node.kind === 'sequence' && node.items.length > 0 && node.items.every((i) => i.kind === 'sequence' && i.items.every((j) => j.kind === 'scalar'));
      const leaves = node.kind === 'mapping' && node.items.every((i) => scalarsOnly(i.value));
      const listOfCollections = node.kind === 'sequence' && node.items.some((i) => i.kind !== 'scalar') && !points;
      if (listOfCollections) {
        // One style for all the items of a list: each on a line if each fits, else all in block style.
        const flowItem = (i) => i.kind === 'scalar' || (i.kind === 'mapping' && i.items.every((k) => scalarsOnly(k.value))) || fits(i, c.depth + 1);
        if (!node.items.every(flowItem)) for (const i of node.items) block.add(i);
        return undefined;
      }
      if (points || leaves || fits(node, c.depth)) {
        node.style = COLLECTION_STYLE.FLOW;
        return VISIT_SKIP;
      }
      return undefined;
    }),
  });
}
function sameValue(a, b) {
  if (a === b) return true;
  if (typeof a !== typeof b || a === null || b === null || typeof a !== 'object') return false;
  if (Array.isArray(a) !== Array.isArray(b)) return false;
  const ka = Object.keys(a), kb = Object.keys(b);
  return ka.length === kb.length && ka.every((k) => Object.prototype.hasOwnProperty.call(b, k) && sameValue(a[k], b[k]));
}

// Scenario object `doc` as YAML text after `header` (readScenarioText's): in the shipped
// scenarios' style, or, should that text not read back as `doc`, in js-yaml's plain one.
export function scenarioText(doc, header = '') {
  let text;
  try {
    text = toYaml(doc);
    if (!sameValue(load(text), JSON.parse(JSON.stringify(doc)))) text = dump(doc, { lineWidth: -1, noRefs: true });
  } catch {
    text = dump(doc, { lineWidth: -1, noRefs: true });
  }
  return header + text;
}
