// A small client of the Foxglove WebSocket protocol (foxglove.websocket.v1), enough for
// rilbed's page: advertised channels, subscriptions, JSON message data, client channels,
// status messages, parameters. No build step, no dependency.
//
//   const client = new FoxgloveClient(url);
//   client.onChannels = (channels) => ...;     // every advertised channel so far (Map topic -> channel)
//   client.onMessage = (topic, tNs, json) => ...;
//   client.onStatus = (level, message) => ...; // 0 info, 1 warning, 2 error
//   client.onClose = (event) => ...;
//   client.subscribe(['/rilbed/poses']);
//   client.publish('/rilbed/console', {command: 'pause', args: []});
//   client.onServerInfo = (info) => ...;      // info.capabilities: 'parameters', 'parametersSubscribe', ...
//   client.onParameterValues = (parameters, id) => ...; // every parameterValues ([{name, value}], id or undefined)
//   await client.getParameters([]);           // [{name, value}, ...] (no names: all)
//   await client.setParameters([{name: 'vision.contrast', value: 1.5}]); // the values after it (refused: unchanged)
//   client.subscribeParameterUpdates(['vision.contrast']); // onParameterValues whenever they change
//
// A client is one connection: its subscription ids count from 0 and its client channel ids
// from 1, as the protocol leaves them to the client. `createSocket(url, protocols)` makes
// the connection (the browser's WebSocket unless a test gives a stand-in).

export const SUBPROTOCOL = 'foxglove.websocket.v1';
const OPEN = 1; // WebSocket.OPEN (not a global in Node, where the tests run)
const MESSAGE_DATA = 0x01; // the binary opcode of a message on a channel (both ways)
const MESSAGE_HEADER_BYTES = 13; // from the server: opcode, subscription id (u32), receive time (u64 ns), little-endian
const CLIENT_HEADER_BYTES = 5; // from a client: opcode, client channel id (u32)

const browserSocket = (url, protocols) => new WebSocket(url, protocols);

export class FoxgloveClient {
  constructor(url, { createSocket = browserSocket } = {}) {
    this.channelsByTopic = new Map();
    this.channelsById = new Map();
    this.wantedTopics = new Set();
    this.subscriptions = new Map(); // subscription id -> topic
    this.subscribedTopics = new Map(); // topic -> subscription id
    this.nextSubscriptionId = 0;
    this.clientChannels = new Map(); // topic -> client channel id
    this.nextClientChannelId = 1;
    this.serverInfo = null;
    this.parameterRequests = new Map(); // request id -> {resolve, reject}
    this.nextRequestId = 1;
    this.decoder = new TextDecoder();
    this.encoder = new TextEncoder();
    this.onChannels = () => {};
    this.onMessage = () => {};
    this.onStatus = () => {};
    this.onOpen = () => {};
    this.onClose = () => {};
    this.onServerInfo = () => {};
    this.onParameterValues = () => {};
    this.ws = createSocket(url, [SUBPROTOCOL]);
    this.ws.binaryType = 'arraybuffer';
    this.ws.onopen = () => this.onOpen();
    this.ws.onclose = (event) => {
      // No answer will come: the requests waiting for one fail.
      for (const { reject } of this.parameterRequests.values()) reject(new Error('the connection closed'));
      this.parameterRequests.clear();
      this.onClose(event);
    };
    this.ws.onmessage = (event) => this.receive(event.data);
  }

  get open() { return this.ws.readyState === OPEN; }

  // Whether the server's serverInfo lists this capability ('parameters', ...).
  can(capability) { return !!this.serverInfo?.capabilities?.includes(capability); }

  close() { this.ws.close(); }

  receive(data) {
    if (typeof data === 'string') return this.receiveText(data);
    const view = new DataView(data);
    if (view.byteLength < MESSAGE_HEADER_BYTES || view.getUint8(0) !== MESSAGE_DATA) return; // only Message Data is used
    const subscriptionId = view.getUint32(1, true);
    const tNs = view.getBigUint64(5, true);
    const topic = this.subscriptions.get(subscriptionId);
    if (topic === undefined) return; // unsubscribed meanwhile
    let message;
    try {
      message = JSON.parse(this.decoder.decode(new Uint8Array(data, MESSAGE_HEADER_BYTES)));
    } catch (e) {
      this.onStatus(2, `${topic}: a message that is not JSON (${e.message})`);
      return;
    }
    this.onMessage(topic, tNs, message);
  }

  receiveText(text) {
    let m;
    try {
      m = JSON.parse(text);
    } catch (e) {
      this.onStatus(2, `the server sent text that is not JSON: ${e.message}`);
      return;
    }
    switch (m.op) {
      case 'serverInfo':
        this.serverInfo = m;
        this.onServerInfo(m);
        break;
      case 'advertise':
        for (const c of m.channels || []) {
          this.channelsByTopic.set(c.topic, c);
          this.channelsById.set(c.id, c);
        }
        this.onChannels(this.channelsByTopic);
        this.subscribeWanted();
        break;
      case 'unadvertise':
        for (const id of m.channelIds || []) {
          const c = this.channelsById.get(id);
          if (!c) continue;
          this.channelsById.delete(id);
          this.channelsByTopic.delete(c.topic);
          const sub = this.subscribedTopics.get(c.topic);
          if (sub !== undefined) {
            this.subscriptions.delete(sub);
            this.subscribedTopics.delete(c.topic);
          }
        }
        this.onChannels(this.channelsByTopic);
        break;
      case 'status':
        this.onStatus(m.level, m.message);
        break;
      case 'parameterValues': {
        const parameters = Array.isArray(m.parameters) ? m.parameters : [];
        this.onParameterValues(parameters, m.id);
        const request = m.id === undefined ? undefined : this.parameterRequests.get(m.id);
        if (request) {
          this.parameterRequests.delete(m.id);
          request.resolve(parameters);
        }
        break;
      }
      default:
        break; // removeStatus, time, ...: not used
    }
  }

  // getParameters / setParameters: a Promise of the parameterValues that answers it (the
  // same id), rejected if the connection is not open or closes first.
  requestParameters(op, fields) {
    if (!this.open) return Promise.reject(new Error('not connected'));
    const id = `p${this.nextRequestId++}`;
    return new Promise((resolve, reject) => {
      this.parameterRequests.set(id, { resolve, reject });
      this.ws.send(JSON.stringify({ op, ...fields, id }));
    });
  }

  // The values of these parameters (none named: all of them), as [{name, value}].
  getParameters(names = []) { return this.requestParameters('getParameters', { parameterNames: names }); }

  // Sets [{name, value}, ...] in one request; resolves to the values after it (on a
  // refusal the server's status says why and the values are the unchanged ones).
  setParameters(parameters) { return this.requestParameters('setParameters', { parameters }); }

  // onParameterValues (without an id) whenever one of these changes, whoever changed it.
  subscribeParameterUpdates(names) {
    if (!this.open) return false;
    this.ws.send(JSON.stringify({ op: 'subscribeParameterUpdates', parameterNames: names }));
    return true;
  }

  unsubscribeParameterUpdates(names) {
    if (!this.open) return false;
    this.ws.send(JSON.stringify({ op: 'unsubscribeParameterUpdates', parameterNames: names }));
    return true;
  }

  // Subscribes to these topics now or as soon as they are advertised.
  subscribe(topics) {
    for (const t of topics) this.wantedTopics.add(t);
    this.subscribeWanted();
  }

  subscribeWanted() {
    if (!this.open) return;
    const subscriptions = [];
    for (const topic of this.wantedTopics) {
      const channel = this.channelsByTopic.get(topic);
      if (!channel || this.subscribedTopics.has(topic)) continue;
      const id = this.nextSubscriptionId++;
      this.subscriptions.set(id, topic);
      this.subscribedTopics.set(topic, id);
      subscriptions.push({ id, channelId: channel.id });
    }
    if (subscriptions.length) this.ws.send(JSON.stringify({ op: 'subscribe', subscriptions }));
  }

  // Publishes `message` (an object, sent as JSON) on a client channel for `topic`.
  publish(topic, message, schemaName = '') {
    if (!this.open) return false;
    let id = this.clientChannels.get(topic);
    if (id === undefined) {
      id = this.nextClientChannelId++;
      this.clientChannels.set(topic, id);
      this.ws.send(JSON.stringify({ op: 'advertise', channels: [{ id, topic, encoding: 'json', schemaName }] }));
    }
    const payload = this.encoder.encode(JSON.stringify(message));
    const frame = new Uint8Array(CLIENT_HEADER_BYTES + payload.length);
    frame[0] = MESSAGE_DATA;
    new DataView(frame.buffer).setUint32(1, id, true);
    frame.set(payload, CLIENT_HEADER_BYTES);
    this.ws.send(frame);
    return true;
  }
}
