// The page's Foxglove client (web/foxglove.js) against a stand-in WebSocket: what it sends
// and what it makes of what the server sends, byte for byte where the protocol is binary.
import test from 'node:test';
import assert from 'node:assert/strict';
import { FoxgloveClient, SUBPROTOCOL } from '../../foxglove.js';

// A WebSocket as the client uses it: readyState, send, the on* handlers; the test plays the server.
class FakeSocket {
  constructor(url, protocols) {
    this.url = url; this.protocols = protocols;
    this.readyState = 0; this.sent = [];
  }
  send(data) { this.sent.push(data); }
  close() { this.readyState = 3; this.onclose?.({ code: 1000 }); }
  // The server's side.
  open() { this.readyState = 1; this.onopen?.(); }
  text(message) { this.onmessage({ data: JSON.stringify(message) }); }
  binary(bytes) { this.onmessage({ data: bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength) }); }
  sentJson() { return this.sent.filter((d) => typeof d === 'string').map((d) => JSON.parse(d)); }
  sentOps(op) { return this.sentJson().filter((m) => m.op === op); }
}

function connect() {
  let socket = null;
  const client = new FoxgloveClient('ws://127.0.0.1:1/ws?token=t', { createSocket: (url, protocols) => (socket = new FakeSocket(url, protocols)) });
  return { client, socket };
}

const CHANNELS = [
  { id: 7, topic: '/rilbed/poses', encoding: 'json', schemaName: 'rilbed.poses' },
  { id: 9, topic: '/rilbed/status', encoding: 'json', schemaName: 'rilbed.status' },
  { id: 11, topic: '/rilbed/world', encoding: 'json', schemaName: 'rilbed.world' },
];

// A server Message Data frame: 0x01, subscription id (u32 LE), receive time (u64 LE ns), payload.
function messageData(subscriptionId, tNs, payload) {
  const body = new TextEncoder().encode(typeof payload === 'string' ? payload : JSON.stringify(payload));
  const frame = new Uint8Array(13 + body.length);
  const view = new DataView(frame.buffer);
  view.setUint8(0, 0x01);
  view.setUint32(1, subscriptionId, true);
  view.setBigUint64(5, tNs, true);
  frame.set(body, 13);
  return frame;
}

test('it asks for the Foxglove subprotocol on the URL given, binary as ArrayBuffers', () => {
  const { socket } = connect();
  assert.equal(socket.url, 'ws://127.0.0.1:1/ws?token=t');
  assert.deepEqual(socket.protocols, [SUBPROTOCOL]);
  assert.equal(SUBPROTOCOL, 'foxglove.websocket.v1');
  assert.equal(socket.binaryType, 'arraybuffer');
});

test('serverInfo: kept, passed on, its capabilities asked by name', () => {
  const { client, socket } = connect();
  const seen = [];
  client.onServerInfo = (info) => seen.push(info.name);
  socket.open();
  assert.equal(client.can('parameters'), false);
  socket.text({ op: 'serverInfo', name: 'rilbed', capabilities: ['clientPublish', 'parameters'], supportedEncodings: ['json'] });
  assert.deepEqual(seen, ['rilbed']);
  assert.equal(client.can('parameters'), true);
  assert.equal(client.can('parametersSubscribe'), false);
});

test('wanted topics are subscribed once advertised, with ids from 0 in one subscribe', () => {
  const { client, socket } = connect();
  socket.open();
  client.subscribe(['/rilbed/status', '/rilbed/poses', '/rilbed/camera']);
  assert.deepEqual(socket.sentOps('subscribe'), [], 'nothing is advertised yet');
  let channels = null;
  client.onChannels = (byTopic) => { channels = [...byTopic.keys()]; };
  socket.text({ op: 'advertise', channels: CHANNELS });
  assert.deepEqual(channels, ['/rilbed/poses', '/rilbed/status', '/rilbed/world']);
  assert.deepEqual(socket.sentOps('subscribe'), [{ op: 'subscribe', subscriptions: [{ id: 0, channelId: 9 }, { id: 1, channelId: 7 }] }]);
  // Advertised again (another channel added): nothing subscribed twice; a new wanted one gets the next id.
  client.subscribe(['/rilbed/world']);
  socket.text({ op: 'advertise', channels: [CHANNELS[0]] });
  assert.deepEqual(socket.sentOps('subscribe').slice(1), [{ op: 'subscribe', subscriptions: [{ id: 2, channelId: 11 }] }]);
});

test('subscription ids are per connection: another client counts from 0 again', () => {
  for (let k = 0; k < 2; ++k) {
    const { client, socket } = connect();
    socket.open();
    client.subscribe(['/rilbed/world']);
    socket.text({ op: 'advertise', channels: CHANNELS });
    assert.deepEqual(socket.sentOps('subscribe')[0].subscriptions, [{ id: 0, channelId: 11 }]);
  }
});

test('nothing is sent before the socket opens; what was wanted is subscribed on the next advertise', () => {
  const { client, socket } = connect();
  client.subscribe(['/rilbed/poses']);
  assert.deepEqual(socket.sent, []);
  assert.equal(client.publish('/rilbed/console', { command: 'pause' }), false);
  socket.open();
  socket.text({ op: 'advertise', channels: CHANNELS });
  assert.deepEqual(socket.sentOps('subscribe')[0].subscriptions, [{ id: 0, channelId: 7 }]);
});

test('a message data frame goes to its subscription\'s topic with its time and JSON', () => {
  const { client, socket } = connect();
  socket.open();
  client.subscribe(['/rilbed/status', '/rilbed/poses']);
  socket.text({ op: 'advertise', channels: CHANNELS });
  const got = [];
  client.onMessage = (topic, tNs, m) => got.push([topic, tNs, m]);
  socket.binary(messageData(1, 1234567890123n, { t_s: 1.5, robots: [] }));
  socket.binary(messageData(0, 5n, { state: 'running' }));
  assert.deepEqual(got, [['/rilbed/poses', 1234567890123n, { t_s: 1.5, robots: [] }], ['/rilbed/status', 5n, { state: 'running' }]]);
});

test('frames it cannot use are dropped; one that is not JSON is a status', () => {
  const { client, socket } = connect();
  socket.open();
  client.subscribe(['/rilbed/poses']);
  socket.text({ op: 'advertise', channels: CHANNELS });
  const got = [], statuses = [];
  client.onMessage = (topic) => got.push(topic);
  client.onStatus = (level, message) => statuses.push([level, message]);
  socket.binary(messageData(5, 0n, {}));                   // no such subscription
  const time = messageData(0, 0n, {}); time[0] = 0x02;      // not Message Data (opcode 2: time)
  socket.binary(time);
  socket.binary(new Uint8Array([1, 0, 0, 0]));              // shorter than a header
  assert.deepEqual(got, []);
  socket.binary(messageData(0, 0n, '{"t_s": '));
  assert.equal(statuses.length, 1);
  assert.equal(statuses[0][0], 2);
  assert.match(statuses[0][1], /^\/rilbed\/poses: a message that is not JSON/);
});

test('unadvertise ends the subscription: its frames are dropped, it is subscribed anew if advertised again', () => {
  const { client, socket } = connect();
  socket.open();
  client.subscribe(['/rilbed/poses']);
  socket.text({ op: 'advertise', channels: CHANNELS });
  const got = [];
  client.onMessage = (topic) => got.push(topic);
  socket.text({ op: 'unadvertise', channelIds: [7] });
  socket.binary(messageData(0, 0n, {}));
  assert.deepEqual(got, []);
  socket.text({ op: 'advertise', channels: [CHANNELS[0]] });
  assert.deepEqual(socket.sentOps('subscribe')[1].subscriptions, [{ id: 1, channelId: 7 }]);
});

test('publish advertises a client channel once, then sends 0x01, the channel id and the JSON', () => {
  const { client, socket } = connect();
  socket.open();
  assert.equal(client.publish('/rilbed/console', { command: 'pause', args: [] }, 'rilbed.console'), true);
  assert.equal(client.publish('/rilbed/console', { command: 'resume', args: [] }, 'rilbed.console'), true);
  assert.equal(client.publish('/rilbed/drive', { id: 3, left: 10, right: 10 }, 'rilbed.drive'), true);
  assert.deepEqual(socket.sentOps('advertise'), [
    { op: 'advertise', channels: [{ id: 1, topic: '/rilbed/console', encoding: 'json', schemaName: 'rilbed.console' }] },
    { op: 'advertise', channels: [{ id: 2, topic: '/rilbed/drive', encoding: 'json', schemaName: 'rilbed.drive' }] },
  ]);
  const frames = socket.sent.filter((d) => typeof d !== 'string');
  assert.equal(frames.length, 3);
  const decode = (f) => {
    const view = new DataView(f.buffer, f.byteOffset, f.byteLength);
    return [view.getUint8(0), view.getUint32(1, true), JSON.parse(new TextDecoder().decode(f.subarray(5)))];
  };
  assert.deepEqual(decode(frames[1]), [0x01, 1, { command: 'resume', args: [] }]);
  assert.deepEqual(decode(frames[2]), [0x01, 2, { id: 3, left: 10, right: 10 }]);
});

test('getParameters and setParameters resolve with the parameterValues of their id', async () => {
  const { client, socket } = connect();
  socket.open();
  const pushed = [];
  client.onParameterValues = (parameters, id) => pushed.push(id);
  const get = client.getParameters(['vision.contrast']);
  const set = client.setParameters([{ name: 'vision.threshold', value: 30 }]);
  const [getRequest] = socket.sentOps('getParameters');
  const [setRequest] = socket.sentOps('setParameters');
  assert.deepEqual(getRequest.parameterNames, ['vision.contrast']);
  assert.deepEqual(setRequest.parameters, [{ name: 'vision.threshold', value: 30 }]);
  assert.notEqual(getRequest.id, setRequest.id);
  // Answers out of order, an update without an id between them.
  socket.text({ op: 'parameterValues', id: setRequest.id, parameters: [{ name: 'vision.threshold', value: 24 }] });
  socket.text({ op: 'parameterValues', parameters: [{ name: 'vision.contrast', value: 2 }] });
  socket.text({ op: 'parameterValues', id: getRequest.id, parameters: [{ name: 'vision.contrast', value: 1.5 }] });
  assert.deepEqual(await set, [{ name: 'vision.threshold', value: 24 }]);
  assert.deepEqual(await get, [{ name: 'vision.contrast', value: 1.5 }]);
  assert.deepEqual(pushed, [setRequest.id, undefined, getRequest.id]);
});

test('parameter requests fail when not connected, or when the connection closes first', async () => {
  const { client, socket } = connect();
  await assert.rejects(client.getParameters([]), /not connected/);
  assert.deepEqual(socket.sent, [], 'a request before the socket opened was sent');
  socket.open();
  const waiting = client.setParameters([{ name: 'vision.contrast', value: 9 }]);
  let closed = null;
  client.onClose = (event) => { closed = event.code; };
  socket.close();
  await assert.rejects(waiting, /the connection closed/);
  assert.equal(closed, 1000);
});

test('parameter updates: subscribed and unsubscribed by name, only while open', () => {
  const { client, socket } = connect();
  assert.equal(client.subscribeParameterUpdates(['vision.contrast']), false);
  socket.open();
  assert.equal(client.subscribeParameterUpdates(['vision.contrast', 'vision.threshold']), true);
  assert.equal(client.unsubscribeParameterUpdates(['vision.threshold']), true);
  assert.deepEqual(socket.sentJson(), [
    { op: 'subscribeParameterUpdates', parameterNames: ['vision.contrast', 'vision.threshold'] },
    { op: 'unsubscribeParameterUpdates', parameterNames: ['vision.threshold'] },
  ]);
});

test('status messages go to onStatus; text that is not JSON is an error status', () => {
  const { client, socket } = connect();
  socket.open();
  const statuses = [];
  client.onStatus = (level, message) => statuses.push([level, message]);
  socket.text({ op: 'status', level: 1, message: 'robot 3 taken over by another client' });
  socket.onmessage({ data: 'not json' });
  assert.deepEqual(statuses[0], [1, 'robot 3 taken over by another client']);
  assert.equal(statuses[1][0], 2);
  assert.match(statuses[1][1], /^the server sent text that is not JSON/);
});
