// The page's link to vas-viewer, run in a Web Worker so that drawing never delays it: it owns the
// WebSocket, acknowledges each frame the moment it arrives (the viewer sends a page at most two
// unacknowledged frames, so nothing queues in the socket), passes frames on to the page, decodes
// meshes, and reconnects when the viewer goes away. Frames are passed on as they arrive, so the
// page draws the newest at its next animation frame even while it is busy drawing; only when the
// page has not taken `PAGE_WINDOW` of them (it is stalled) does the worker keep just the newest
// until the page catches up.
//
// A scene arrives as one JSON message (`type: "scene"`, with `meshes`: how many follow) and then
// that many binary messages, one mesh each (little-endian, 4-byte aligned so typed arrays view it
// in place):
//   u32 mesh index, u32 vertex count, u32 normal count (0 or the vertex count), u32 triangle count,
//   f32 positions[3 * vertices], f32 normals[3 * normals], u32 indices[3 * triangles].
//
// A frame arrives 1000 times a second and is drawn at most at the display's rate, so the worker
// does not parse it: the viewer starts every frame message with its scene and the newest publish
// stamp in it (`{"type":"frame","published_ns":N,"scene":N,`), which is all the worker reads, and
// the page parses only the frame it draws.
//
// To the page (postMessage):
//   { kind: 'open', open }                  the WebSocket opened (true) or closed (false)
//   { kind: 'message', message, arrivedMs } a status, event, reply or warning, in order
//   { kind: 'scene', scene, meshes }        a scene and its meshes (their buffers transferred)
//   { kind: 'frame', text, scene, arrivedMs, transport, superseded }
//       a frame: its message as sent (JSON text) and the scene version it names; `transport`
//       lists, per frame that arrived since the last one posted, the milliseconds from the
//       server's publish to its arrival here; `superseded` counts those this one replaced while
//       the page was stalled
//   { kind: 'hand_joints_dropped' }         a hand-joints message was dropped (see below)
// From the page:
//   { kind: 'command', command }      sent to the viewer
//   { kind: 'took' }                  the page took a frame posted
//   { kind: 'hand_joints', buffer }   a binary hand-joints message (xr.js), sent to the viewer
//       unless the socket already holds more than `HAND_JOINTS_BUFFERED` bytes not yet sent: a
//       newer one follows within one XR frame, so an old one is dropped rather than queued
//
// Times are wall clock in milliseconds since the Unix epoch.

const RECONNECT_MS = 1000;
// Frames posted to the page and not yet taken, at most: a quarter of a second at 1 kHz.
const PAGE_WINDOW = 256;
const ACK = JSON.stringify({ type: 'ack' });
// The start of every frame message: its newest publish stamp (ns) and its scene version.
const FRAME_HEAD = /^\{"type":"frame","published_ns":(\d+),"scene":(\d+),/;
// Bytes the socket may hold unsent before hand joints are dropped: some ten XR frames of both hands.
const HAND_JOINTS_BUFFERED = 16 * 1024;

let socket = null;
let pendingScene = null;
// The newest frame not posted yet, and what the page is told with it.
let newest = null;
let transport = [];
let superseded = 0;
// Frames posted and not yet taken by the page.
let untaken = 0;

const wallClockMs = () => performance.timeOrigin + performance.now();

function connect() {
  const scheme = self.location.protocol === 'https:' ? 'wss:' : 'ws:';
  socket = new WebSocket(`${scheme}//${self.location.host}/ws`);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => postMessage({ kind: 'open', open: true });
  socket.onclose = () => {
    socket = null;
    pendingScene = null;
    newest = null;
    postMessage({ kind: 'open', open: false });
    setTimeout(connect, RECONNECT_MS);
  };
  socket.onmessage = (message) => receive(message.data, wallClockMs());
}

function receive(data, arrivedMs) {
  if (data instanceof ArrayBuffer) {
    receiveMesh(data);
    return;
  }
  const head = FRAME_HEAD.exec(data);
  if (head) {
    socket.send(ACK);
    // Nanoseconds since the epoch exceed a double's integers: the stamp is good to a microsecond.
    transport.push(arrivedMs - Number(head[1]) / 1e6);
    if (newest) superseded += 1;
    newest = { text: data, scene: Number(head[2]), arrivedMs };
    postFrame();
    return;
  }
  const message = JSON.parse(data);
  switch (message.type) {
    case 'scene':
      pendingScene = { scene: message, meshes: new Array(message.meshes), received: 0 };
      if (message.meshes === 0) finishScene();
      break;
    default:
      postMessage({ kind: 'message', message, arrivedMs });
  }
}

function postFrame() {
  if (!newest || untaken >= PAGE_WINDOW) return;
  postMessage({ kind: 'frame', ...newest, transport, superseded });
  newest = null;
  transport = [];
  superseded = 0;
  untaken += 1;
}

function receiveMesh(buffer) {
  const pending = pendingScene;
  if (!pending) return;
  const [index, vertices, normals, triangles] = new Uint32Array(buffer, 0, 4);
  if (index >= pending.meshes.length || pending.meshes[index]) return;
  let offset = 16;
  const positions = new Float32Array(buffer, offset, 3 * vertices);
  offset += 12 * vertices;
  const normalArray = new Float32Array(buffer, offset, 3 * normals);
  offset += 12 * normals;
  const indices = new Uint32Array(buffer, offset, 3 * triangles);
  pending.meshes[index] = { positions, normals: normals > 0 ? normalArray : null, indices };
  pending.received += 1;
  if (pending.received === pending.meshes.length) finishScene();
}

function finishScene() {
  const { scene, meshes } = pendingScene;
  pendingScene = null;
  // A frame of the old scene is no use to the page any more.
  newest = null;
  const buffers = meshes.map((mesh) => mesh.positions.buffer);
  postMessage({ kind: 'scene', scene, meshes }, buffers);
}

self.onmessage = ({ data }) => {
  if (data.kind === 'took') {
    untaken -= 1;
    postFrame();
  } else if (data.kind === 'hand_joints') {
    if (socket?.readyState === WebSocket.OPEN && socket.bufferedAmount <= HAND_JOINTS_BUFFERED) {
      socket.send(data.buffer);
    } else {
      postMessage({ kind: 'hand_joints_dropped' });
    }
  } else if (data.kind === 'command') {
    if (socket?.readyState === WebSocket.OPEN) {
      socket.send(JSON.stringify(data.command));
    } else {
      const warning = { type: 'warning', message: `not connected: ${data.command.type} not sent` };
      postMessage({ kind: 'message', message: warning, arrivedMs: wallClockMs() });
    }
  }
};

connect();
