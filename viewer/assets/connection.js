// The page's WebSocket to the viewer: decodes its messages, sends commands, and reconnects when
// the viewer goes away.
//
// Each handler gets the message and the wall-clock time it arrived. A scene arrives as one JSON
// message (`type: "scene"`, with `meshes`: how many follow) and then
// that many binary messages, one mesh each (little-endian, 4-byte aligned so typed arrays view it
// in place):
//   u32 mesh index, u32 vertex count, u32 normal count (0 or the vertex count), u32 triangle count,
//   f32 positions[3 * vertices], f32 normals[3 * normals], u32 indices[3 * triangles].

const RECONNECT_MS = 1000;

export class Connection {
  // `handlers` has one function per message type (status, scene, frame, event, reply,
  // warning) and `open(bool)` for the connection itself.
  constructor(handlers) {
    this.handlers = handlers;
    this.pendingScene = null;
    this.socket = null;
    this.connect();
  }

  connect() {
    const scheme = location.protocol === 'https:' ? 'wss:' : 'ws:';
    const socket = new WebSocket(`${scheme}//${location.host}/ws`);
    socket.binaryType = 'arraybuffer';
    socket.onopen = () => this.handlers.open(true);
    socket.onclose = () => {
      this.socket = null;
      this.pendingScene = null;
      this.handlers.open(false);
      setTimeout(() => this.connect(), RECONNECT_MS);
    };
    socket.onmessage = (message) => this.receive(message.data, performance.timeOrigin + performance.now());
    this.socket = socket;
  }

  // Sends a command; false when there is no connection to send it on.
  send(command) {
    if (!this.socket || this.socket.readyState !== WebSocket.OPEN) return false;
    this.socket.send(JSON.stringify(command));
    return true;
  }

  // `arrivedMs`: when the message arrived, wall clock in milliseconds since the Unix epoch.
  receive(data, arrivedMs) {
    if (data instanceof ArrayBuffer) {
      this.receiveMesh(data);
      return;
    }
    const message = JSON.parse(data);
    if (message.type === 'scene') {
      this.pendingScene = { scene: message, meshes: new Array(message.meshes), received: 0 };
      if (message.meshes === 0) this.finishScene();
      return;
    }
    const handler = this.handlers[message.type];
    if (handler) handler(message, arrivedMs);
  }

  receiveMesh(buffer) {
    const pending = this.pendingScene;
    if (!pending) return;
    const [index, vertices, normals, triangles] = new Uint32Array(buffer, 0, 4);
    let offset = 16;
    const positions = new Float32Array(buffer, offset, 3 * vertices);
    offset += 12 * vertices;
    const normalArray = new Float32Array(buffer, offset, 3 * normals);
    offset += 12 * normals;
    const indices = new Uint32Array(buffer, offset, 3 * triangles);
    if (index >= pending.meshes.length || pending.meshes[index]) return;
    pending.meshes[index] = { positions, normals: normals > 0 ? normalArray : null, indices };
    pending.received += 1;
    if (pending.received === pending.meshes.length) this.finishScene();
  }

  finishScene() {
    const { scene, meshes } = this.pendingScene;
    this.pendingScene = null;
    this.handlers.scene(scene, meshes);
  }
}
