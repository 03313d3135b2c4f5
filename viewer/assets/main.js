// The viewer page: receives the scene and frames from vas-viewer over a WebSocket and draws the
// newest frame at the display's rate, on the screen or in a WebXR session (where xr.js also sends
// the user's tracked hands to the server, each XR frame).
//
// Frames arrive faster or slower than the display draws; only the newest is drawn (a frame
// that arrived while another was waiting replaces it, here or in the link's worker). The latency shown is from the input
// sample a hand frame answers (its tracker timestamp, wall clock) to the moment the frame was
// drawn, for live input only (see `LIVE_INPUT_MS`). Everything tests look at is on
// `window.vasViewer`.
//
// In a scene of several users, the headset's hands are those of the user the page's address
// names (`?user=NAME`), or of the scene's first user without one; a name the scene does not have
// is refused on the panel, and no hands are sent.

import { Connection } from './connection.js';
import { Panel } from './panel.js';
import { COLOURS, PALETTE, View, clearanceColour, stateOf, userColour } from './view.js';
import { setupXr } from './xr.js';

// A hand frame published more than this after its tracker sample's stamp answers input that is
// not live: a lockstep replay stamps its samples in the past (`vas-client replay`), so that the
// time since the stamp says nothing of the latency. The server answers live input within a few
// of its frames, far below this.
const LIVE_INPUT_MS = 1000;
// Latencies kept for the median shown and for tests.
const LATENCY_WINDOW = 200;
// Events kept for tests (the panel shows fewer).
const EVENT_WINDOW = 1000;
// Frames whose timing is kept for the browser benchmark (B9 in BENCHMARKS.md).
const TIMING_WINDOW = 100000;

// The user named in the page's address, or null.
const REQUESTED_USER = new URLSearchParams(window.location.search).get('user');

const view = new View(document.getElementById('view'));
const state = {
  open: false,
  server: false,
  scene: null,
  sceneNames: [],
  // The name the server offers its current scene under (null if not offered), and the sliding
  // metaphor the server uses.
  currentScene: null,
  metaphor: null,
  // The sides (`right`, `left`) whose hands have answered input since the scene started.
  handsSeen: [],
  // The user the headset's hands are sent as: name and index in the scene's users (index null:
  // the scene has no such user, and no hands are sent).
  xrUser: { name: REQUESTED_USER, index: null },
  waiting: null, // the newest frame not drawn yet: { text, arrivedMs }
  newest: null, // the newest frame received
  received: { frames: 0, events: 0, scenes: 0 },
  drawn: { frames: 0, lastParts: 0, lastHand: 0 },
  events: [],
  replies: [],
  warnings: [],
  latencies: [],
  xrFrames: 0,
  fps: 0,
  // Per frame, in milliseconds: from the server's publish to its arrival at the page's link
  // (transport), and from that arrival to the end of the animation frame that drew it (draw); and
  // the frames a newer one replaced before they were drawn, and the drawn frames that were late:
  // an animation frame began after they arrived and did not draw them.
  timing: { transport: [], draw: [], superseded: 0, late: 0 },
};

const connection = new Connection({
  open(open) {
    state.open = open;
    if (!open) state.server = false;
    panel.showStatus(state.open, state.server);
  },
  status(message) {
    state.server = message.server;
    state.sceneNames = message.scene_names;
    state.currentScene = message.scene;
    state.metaphor = message.metaphor;
    panel.showStatus(state.open, state.server);
    panel.showSceneNames(message.scene_names, message.scene);
    panel.showMetaphor(message.metaphor);
  },
  scene(scene, meshes) {
    state.scene = scene;
    state.waiting = null;
    state.newest = null;
    state.received.scenes += 1;
    state.handsSeen = [];
    panel.showHands(state.handsSeen);
    view.setScene(scene, meshes);
    panel.showScene(scene.name);
    showLegend(scene.users ?? []);
    chooseXrUser(scene.users ?? []);
  },
  // A frame as the link's worker posts it: its JSON text, parsed only if it is drawn.
  frame(text, scene, arrivedMs, transport, superseded) {
    for (const milliseconds of transport) keep(state.timing.transport, milliseconds, TIMING_WINDOW);
    state.timing.superseded += superseded;
    if (scene !== state.scene?.version) return;
    state.received.frames += 1;
    if (state.waiting) state.timing.superseded += 1;
    state.waiting = { text, arrivedMs };
    state.newest = state.waiting;
  },
  event(event) {
    state.received.events += 1;
    keep(state.events, event.text, EVENT_WINDOW);
    panel.addEvent(event.text);
    if (event.point && (event.kind === 'contact_begin' || event.kind === 'contact_end')) {
      view.addMarker(event.point, event.kind === 'contact_begin', performance.now(), event.part);
    }
  },
  reply(reply) {
    state.replies.push(reply);
    panel.showReply(reply.message, !reply.ok);
  },
  warning(warning) {
    state.warnings.push(warning.message);
    panel.showReply(warning.message, true);
  },
});
const panel = new Panel((command) => connection.send(command));
// A colour number (0xrrggbb) as CSS writes it.
const cssHex = (colour) => `#${colour.toString(16).padStart(6, '0')}`;
const xr = setupXr(view, panel, connection);
// The legend: the palette, then in a scene of several users each user's hand colour and name.
function showLegend(users) {
  const named = users.length > 1 ? users : [];
  const hands = named.map((name, user) => ({ css: cssHex(userColour(user)), words: `${name}'s hands` }));
  panel.showLegend(
    [...PALETTE.map(({ colour, words }) => ({ css: cssHex(colour), words })), ...hands],
    [0, 0.5, 1].map((closeness) => clearanceColour(closeness).getStyle()),
  );
}
showLegend([]);

// Chooses the user of `users` (the scene's) whose hands the headset sends.
function chooseXrUser(users) {
  const index = REQUESTED_USER === null ? 0 : users.indexOf(REQUESTED_USER);
  state.xrUser = { name: REQUESTED_USER ?? users[0] ?? null, index: index >= 0 ? index : null };
  xr.hands.setUser(state.xrUser.index);
  if (index < 0) {
    const message = `no user "${REQUESTED_USER}" in this scene (its users: ${users.join(', ')}): ` +
      'the headset\'s hands are not sent';
    state.warnings.push(message);
    panel.showReply(message, true);
  }
}

// Wall clock in milliseconds since the Unix epoch, as the frames' timestamps count it.
const wallClockMs = () => performance.timeOrigin + performance.now();

let fpsWindow = { start: performance.now(), frames: 0 };
// When the last animation frame began, wall clock.
let lastStartMs = 0;
view.renderer.setAnimationLoop((now, xrFrame) => {
  const startMs = wallClockMs();
  if (xrFrame) xr.frame(xrFrame);
  const waiting = state.waiting;
  state.waiting = null;
  const frame = waiting && parsed(waiting);
  if (frame) view.applyFrame(frame);
  view.render(now);
  if (view.renderer.xr.isPresenting) state.xrFrames += 1;
  if (frame) {
    noteDrawn(frame);
    keep(state.timing.draw, wallClockMs() - waiting.arrivedMs, TIMING_WINDOW);
    if (lastStartMs > waiting.arrivedMs) state.timing.late += 1;
  }
  lastStartMs = startMs;
  fpsWindow.frames += 1;
  if (now - fpsWindow.start >= 1000) {
    state.fps = (fpsWindow.frames * 1000) / (now - fpsWindow.start);
    fpsWindow = { start: now, frames: 0 };
    panel.showPerf(state.fps, median(state.latencies));
  }
});

// The frame message `received` holds, parsed once.
function parsed(received) {
  received.frame ??= JSON.parse(received.text);
  return received.frame;
}

// Records that `frame` is on the screen, the hands that answered input, and the latency of a
// hand frame drawn for the first time that answers live input.
function noteDrawn(frame) {
  state.drawn.frames += 1;
  state.drawn.lastParts = frame.parts?.frame ?? state.drawn.lastParts;
  for (const hand of frame.hands) {
    noteHandSeen(hand);
    if (hand.frame <= state.drawn.lastHand) continue;
    state.drawn.lastHand = hand.frame;
    const live = (hand.published_ns - hand.tracker_ns) / 1e6 <= LIVE_INPUT_MS;
    if (hand.tracker_ns > 0 && live) {
      keep(state.latencies, wallClockMs() - hand.tracker_ns / 1e6, LATENCY_WINDOW);
    }
  }
}

// Adds the side of `hand` (a frame's hand) to the hands seen once it answers input, with its
// user's name in a scene of several users ("anna's right").
function noteHandSeen(hand) {
  const ofScene = state.scene?.hands.find(
    (scene) => scene.hand === hand.hand && scene.user === hand.user,
  );
  const named = (state.scene?.users ?? []).length > 1;
  const side = ofScene && (named ? `${ofScene.user_name}'s ${ofScene.side}` : ofScene.side);
  if (!hand.answered || !side || state.handsSeen.includes(side)) return;
  state.handsSeen = [...state.handsSeen, side];
  panel.showHands(state.handsSeen);
}

// Appends `value` to `values`, keeping at least the newest `window` of them (trimmed in batches,
// so that appending stays cheap however long the window).
function keep(values, value, window) {
  values.push(value);
  if (values.length >= 2 * window) values.splice(0, values.length - window);
}

function median(values) {
  if (values.length === 0) return null;
  const sorted = [...values].sort((a, b) => a - b);
  return sorted[Math.floor(sorted.length / 2)];
}

const hex = (colour) => `#${colour.getHexString()}`;

// What the page draws, for tests and for a look from the console.
window.vasViewer = {
  get open() { return state.open; },
  get server() { return state.server; },
  get scene() { return state.scene && { version: state.scene.version, name: state.scene.name }; },
  get sceneNames() { return state.sceneNames; },
  get currentScene() { return state.currentScene; },
  get metaphor() { return state.metaphor; },
  get handsSeen() { return [...state.handsSeen]; },
  get xrUser() { return { ...state.xrUser }; },
  // What the panel shows: its scene and metaphor menus' selections, its hands line, its legend's
  // swatches (CSS backgrounds, as computed) and its latency figure.
  panel() {
    const element = (id) => document.getElementById(id);
    return {
      scene: element('scenes').value,
      metaphor: element('metaphor').value,
      hands: element('hands').textContent,
      legend: [...element('legend').querySelectorAll('.swatch')].map(
        (swatch) => getComputedStyle(swatch).backgroundColor,
      ),
      perf: element('perf').textContent,
    };
  },
  get received() {
    const newest = state.newest && parsed(state.newest);
    const hands = newest?.hands ?? [];
    return {
      ...state.received,
      lastParts: newest?.parts?.frame ?? 0,
      lastHand: hands.length > 0 ? Math.max(...hands.map((hand) => hand.frame)) : 0,
    };
  },
  get drawn() { return { ...state.drawn }; },
  get events() { return [...state.events]; },
  get replies() { return [...state.replies]; },
  get warnings() { return [...state.warnings]; },
  get latencies() { return [...state.latencies]; },
  get xrFrames() { return state.xrFrames; },
  // Hand-joints messages handed to the link per side, and those it dropped for a slow socket.
  get handJoints() {
    return { posted: { ...xr.hands.posted }, dropped: connection.handJointsDropped };
  },
  get timing() {
    const { transport, draw, superseded, late } = state.timing;
    return { transport: [...transport], draw: [...draw], superseded, late };
  },
  resetTiming() { state.timing = { transport: [], draw: [], superseded: 0, late: 0 }; },
  get fps() { return state.fps; },
  // Every contact marker: the part it is kept on (null: none), where it is drawn in the vas world,
  // where it is in its part's frame, and its colour.
  get markers() {
    return view.markers.map((marker) => ({
      part: marker.userData.part,
      position: view.markerPosition(marker).toArray(),
      local: marker.position.toArray(),
      colour: hex(marker.material.color),
    }));
  },
  // Every part as drawn: pose in the vas world, state and colour.
  parts() {
    return view.parts.map((mesh) => ({
      id: mesh.userData.id,
      name: mesh.name,
      visible: mesh.visible,
      position: mesh.position.toArray(),
      quaternion: mesh.quaternion.toArray(),
      state: mesh.userData.state,
      colour: hex(mesh.material.color),
    }));
  },
  // Every user's name label as drawn, by its hand's key (`handKey`).
  names() {
    return [...view.nameLabels.entries()].map(([hand, label]) => ({
      hand,
      text: label.userData.text,
      colour: label.userData.colour,
      visible: label.visible,
      position: label.position.toArray(),
    }));
  },
  // Every hand's segments as drawn.
  hands() {
    return [...view.hands.entries()].map(([hand, segments]) => ({
      hand,
      segments: segments.map((mesh) => ({
        visible: mesh.visible,
        position: mesh.position.toArray(),
        quaternion: mesh.quaternion.toArray(),
        colour: hex(mesh.material.color),
      })),
    }));
  },
  // The pixel (CSS pixels from the canvas's top left) a vas world point is drawn at.
  project: (x, y, z) => view.project(x, y, z),
  // The canvas's place on the page, in CSS pixels.
  canvasRect() {
    const { left, top, width, height } = view.renderer.domElement.getBoundingClientRect();
    return { left, top, width, height };
  },
  stateOf,
  // Each part state's colour (and the hand's and the markers'), by name, as `#rrggbb`.
  colours: Object.fromEntries(Object.entries(COLOURS).map(([key, colour]) => [key, cssHex(colour)])),
};
