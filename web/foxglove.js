// A small client of the Foxglove WebSocket protocol (foxglove.websocket.v1), enough for
// rilbed's page: advertised channels, subscriptions, JSON message data, client channels,
// status messages. No build step, no dependency.
//
//   const client = new FoxgloveClient(url);
//   client.onChannels = (channels) => ...;     // every advertised channel so far (Map topic -> channel)
//   client.onMessage = (topic, tNs, json) => ...;
//   client.onStatus = (level, message) => ...; // 0 info, 1 warning, 2 error
//   client.onClose = (event) => ...;
//   client.subscribe(['/rilbed/poses']);
//   client.publish('/rilbed/console', {command: 'pause', args: []});

export const SUBPROTOCOL = 'foxglove.websocket.v1';

export class FoxgloveClient {
  constructor(url) {
    this.channelsByTopic = new Map();
    this.channelsById = new Map();
    this.wantedTopics = new Set();
    this.subscriptions = new Map(); // subscription id -> topic
    this.subscribedTopics = new Map(); // topic -> subscription id
    this.nextSubscriptionId = 1;
    this.clientChannels = new Map(); // topic -> client channel id
    this.nextClientChannelId = 1;
    this.serverInfo = null;
    this.decoder = new TextDecoder();
    this.encoder = new TextEncoder();
    this.onChannels = () => {};
    this.onMessage = () => {};
    this.onStatus = () => {};
    this.onOpen = () => {};
    this.onClose = () => {};
    this.ws = new WebSocket(url, [SUBPROTOCOL]);
    this.ws.binaryType = 'arraybuffer';
    this.ws.onopen = () => this.onOpen();
    this.ws.onclose = (event) => this.onClose(event);
    this.ws.onmessage = (event) => this.receive(event.data);
  }

  get open() { return this.ws.readyState === WebSocket.OPEN; }

  close() { this.ws.close(); }

  receive(data) {
    if (typeof data === 'string') return this.receiveText(data);
    const view = new DataView(data);
    if (view.byteLength < 13 || view.getUint8(0) !== 1) return; // only Message Data is used
    const subscriptionId = view.getUint32(1, true);
    const tNs = view.getBigUint64(5, true);
    const topic = this.subscriptions.get(subscriptionId);
    if (topic === undefined) return; // unsubscribed meanwhile
    let message;
    try {
      message = JSON.parse(this.decoder.decode(new Uint8Array(data, 13)));
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
      default:
        break; // removeStatus, parameterValues, ...: not used
    }
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
    const frame = new Uint8Array(5 + payload.length);
    frame[0] = 1;
    new DataView(frame.buffer).setUint32(1, id, true);
    frame.set(payload, 5);
    this.ws.send(frame);
    return true;
  }
}
