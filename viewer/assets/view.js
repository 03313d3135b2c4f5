// The three.js view: the parts and hands the server published, drawn where it put them.
//
// Everything vas sends lives in `world`, a group in vas's frame (metres, z up). On a screen the
// group is left as it is and the camera's up is z; in a WebXR session (y up) xr.js turns the
// group. Nothing here computes a pose: each part and each hand segment is placed at the pose of
// the newest frame, and coloured by the state flags the server set; clearance pairs are drawn as
// the segments between their closest points, labelled in millimetres.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

// PartState flags, as in protocol/src/output.rs.
const PART_GRASPED = 1;
const PART_TOUCHING = 2;
const PART_SLIDING = 4;
const PART_PUSHED = 8;

// Every colour the page draws with, and its words in the panel's legend (panel.js builds the
// legend from this list, so that the two cannot differ). Part states first, in `stateOf`'s order.
export const PALETTE = [
  { key: 'sliding', colour: 0xb066f0, words: 'held, sliding' },
  { key: 'grasped', colour: 0x2fd15a, words: 'grasped' },
  { key: 'pushed', colour: 0x3fc6d9, words: 'pushed' },
  { key: 'touching', colour: 0xf2b233, words: 'touching' },
  { key: 'resting', colour: 0x8c9aab, words: 'resting' },
  { key: 'hand', colour: 0xd8a27e, words: 'hand' },
  { key: 'handTouching', colour: 0xff7a45, words: 'hand segment touching' },
  { key: 'contactBegin', colour: 0xff3b30, words: 'contact begins' },
  { key: 'contactEnd', colour: 0x35a7ff, words: 'contact ends' },
];
// The palette's colours by key.
export const COLOURS = Object.fromEntries(PALETTE.map(({ key, colour }) => [key, colour]));
// Each user's hand colour, by the user's index: the first user's is the palette's hand colour,
// so that a scene of one user looks as it always did.
export const USER_COLOURS = [COLOURS.hand, 0x9fb4ff, 0xb6e07a, 0xe59ad6];
// A user's name label: its height above the palm (metres).
const NAME_ABOVE_PALM = 0.06;

// The key of a scene's hand in `View.hands`: user × 2 + side code (a user has at most one hand
// of each side), so that the first user's hands keep their side's code as their key.
export function handKey(user, side) {
  return user * 2 + side;
}

// The hand colour of user `user`.
export function userColour(user) {
  return USER_COLOURS[user % USER_COLOURS.length];
}
// How long a contact marker stays, in milliseconds.
const MARKER_MS = 1500;
// A clearance label's height in the world (metres) and its canvas's size in pixels.
const LABEL_HEIGHT = 0.012;
const LABEL_PIXELS = [160, 48];

// A clearance pair's colour at `closeness` (its distance over the threshold, 0 to 1): red when
// touching through yellow to green at the threshold.
export function clearanceColour(closeness) {
  return new THREE.Color().setHSL(closeness / 3, 0.9, 0.5);
}

// A part's state from its flags. The server flags sliding only on a held part, so sliding shows
// over grasped (a colour of its own: held and sliding); a pushed part also touches the hand, so
// pushed shows over touching.
export function stateOf(flags) {
  if (flags & PART_SLIDING) return 'sliding';
  if (flags & PART_GRASPED) return 'grasped';
  if (flags & PART_PUSHED) return 'pushed';
  if (flags & PART_TOUCHING) return 'touching';
  return 'resting';
}

export class View {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.xr.enabled = true;
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0x1d2126);
    this.world = new THREE.Group();
    this.scene.add(this.world);

    this.camera = new THREE.PerspectiveCamera(45, 1, 0.01, 100);
    this.camera.up.set(0, 0, 1);
    this.camera.position.set(0.5, -0.8, 0.5);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);

    const sky = new THREE.HemisphereLight(0xffffff, 0x445060, 2.0);
    sky.position.set(0, 0, 1);
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(1, -1.5, 2);
    const floor = new THREE.GridHelper(2, 40, 0x59636e, 0x3a4149);
    floor.rotation.x = Math.PI / 2;
    this.world.add(sky, sun, floor);

    this.parts = [];
    this.hands = new Map();
    // A name label per hand, by the hands' key, in a scene of several users.
    this.nameLabels = new Map();
    this.markers = [];
    // One segment and label per clearance pair drawn, reused from frame to frame.
    this.gaps = [];
    this.sceneName = null;
    this.fitPending = false;

    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const { clientWidth: width, clientHeight: height } = this.container;
    if (width === 0 || height === 0 || this.renderer.xr.isPresenting) return;
    this.renderer.setSize(width, height);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  // Replaces the drawn scene by `scene` (the viewer's scene message) and its `meshes`.
  setScene(scene, meshes) {
    for (const mesh of [...this.markers, ...this.parts]) this.dispose(mesh);
    this.markers = [];
    for (const hand of this.hands.values()) hand.forEach((segment) => this.dispose(segment));
    for (const label of this.nameLabels.values()) this.dispose(label);
    const geometries = meshes.map(geometryOf);
    this.parts = scene.parts.map((part) => {
      const mesh = this.addMesh(geometries[part.mesh], COLOURS.resting);
      mesh.name = part.name;
      Object.assign(mesh.userData, { id: part.id, state: 'resting' });
      return mesh;
    });
    this.hands = new Map(
      scene.hands.map((hand) => [
        handKey(hand.user, hand.hand),
        hand.segments.map((mesh) => this.addMesh(geometries[mesh], userColour(hand.user))),
      ]),
    );
    // Names over the hands when the scene has several users.
    const named = (scene.users ?? []).length > 1 ? scene.hands : [];
    this.nameLabels = new Map(
      named.map((hand) => [handKey(hand.user, hand.hand), this.addName(hand.user_name, hand.user)]),
    );
    // A new scene is framed once its parts have poses; the same scene again keeps the camera.
    if (scene.name !== this.sceneName) this.fitPending = true;
    this.sceneName = scene.name;
  }

  // A mesh hidden until its first pose (a part without geometry stays hidden). Both sides are
  // drawn: CAD meshes may be polygon soups whose winding means nothing.
  addMesh(geometry, colour) {
    const material = new THREE.MeshStandardMaterial({
      color: colour,
      roughness: 0.6,
      metalness: 0.05,
      side: THREE.DoubleSide,
    });
    const mesh = new THREE.Mesh(geometry ?? new THREE.BufferGeometry(), material);
    mesh.visible = false;
    mesh.userData.hasGeometry = geometry !== undefined;
    this.world.add(mesh);
    return mesh;
  }

  dispose(mesh) {
    mesh.removeFromParent();
    mesh.geometry.dispose();
    mesh.material.dispose();
  }

  // Places every part and hand segment at its pose in `frame` (the viewer's frame message).
  applyFrame(frame) {
    for (const part of frame.parts?.parts ?? []) {
      const mesh = this.parts[part.id];
      if (!mesh) continue;
      place(mesh, part.position, part.rotation);
      const state = stateOf(part.flags);
      if (state !== mesh.userData.state) {
        mesh.userData.state = state;
        mesh.material.color.setHex(COLOURS[state]);
      }
    }
    for (const hand of frame.hands) {
      const key = handKey(hand.user, hand.hand);
      const segments = this.hands.get(key) ?? [];
      hand.segments.forEach((pose, index) => {
        const mesh = segments[index];
        if (!mesh) return;
        place(mesh, pose.position, pose.rotation);
        const touching = (hand.touching >> index) & 1;
        mesh.material.color.setHex(touching ? COLOURS.handTouching : userColour(hand.user));
      });
      const label = this.nameLabels.get(key);
      const palm = hand.segments[0];
      if (label && palm) {
        label.position.set(palm.position[0], palm.position[1], palm.position[2] + NAME_ABOVE_PALM);
        label.visible = true;
      }
    }
    this.drawClearance(frame.clearance);
    if (this.fitPending && this.parts.some((mesh) => mesh.visible)) {
      this.fitPending = false;
      this.fit();
    }
  }

  // Draws each clearance pair's closest points as a segment with its distance in millimetres,
  // red when touching through yellow to green at the threshold; a stale pair (measured on an
  // earlier frame) is drawn faint. Drawn over the parts: the tightest spot is often inside a
  // hole.
  drawClearance(clearance) {
    const pairs = clearance?.pairs ?? [];
    while (this.gaps.length < pairs.length) this.gaps.push(this.addGap());
    this.gaps.forEach((gap, index) => {
      const pair = pairs[index];
      gap.line.visible = gap.label.visible = pair !== undefined;
      if (!pair) return;
      const positions = gap.line.geometry.attributes.position;
      positions.setXYZ(0, ...pair.point);
      positions.setXYZ(1, ...pair.other_point);
      positions.needsUpdate = true;
      gap.line.geometry.computeBoundingSphere();
      const closeness = Math.min(Math.max(pair.distance / clearance.threshold, 0), 1);
      const colour = clearanceColour(closeness);
      const opacity = pair.stale ? 0.35 : 1;
      gap.line.material.color.copy(colour);
      gap.line.material.opacity = opacity;
      gap.label.material.opacity = opacity;
      gap.label.position.set(...pair.point.map((c, i) => (c + pair.other_point[i]) / 2));
      const text = `${(pair.distance * 1000).toFixed(1)} mm`;
      if (text !== gap.text || colour.getHex() !== gap.colour) {
        gap.text = text;
        gap.colour = colour.getHex();
        drawLabel(gap.canvas, text, colour.getStyle());
        gap.label.material.map.needsUpdate = true;
      }
    });
  }

  // A label naming user `user` in their colour, hidden until their hand is placed.
  addName(name, user) {
    const canvas = document.createElement('canvas');
    [canvas.width, canvas.height] = LABEL_PIXELS;
    const colour = `#${userColour(user).toString(16).padStart(6, '0')}`;
    drawLabel(canvas, name, colour);
    const material = new THREE.SpriteMaterial({
      map: new THREE.CanvasTexture(canvas),
      transparent: true,
      depthTest: false,
    });
    const label = new THREE.Sprite(material);
    label.scale.set((LABEL_HEIGHT * LABEL_PIXELS[0]) / LABEL_PIXELS[1], LABEL_HEIGHT, 1);
    label.renderOrder = 2;
    label.visible = false;
    Object.assign(label.userData, { text: name, colour });
    // Its own geometry: `dispose` frees it, and sprites share one unless given theirs.
    label.geometry = label.geometry.clone();
    this.world.add(label);
    return label;
  }

  // A clearance segment and its label, hidden until used.
  addGap() {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(6), 3));
    const lineMaterial = new THREE.LineBasicMaterial({ transparent: true, depthTest: false });
    const line = new THREE.Line(geometry, lineMaterial);
    const canvas = document.createElement('canvas');
    [canvas.width, canvas.height] = LABEL_PIXELS;
    const labelMaterial = new THREE.SpriteMaterial({
      map: new THREE.CanvasTexture(canvas),
      transparent: true,
      depthTest: false,
    });
    const label = new THREE.Sprite(labelMaterial);
    label.scale.set((LABEL_HEIGHT * LABEL_PIXELS[0]) / LABEL_PIXELS[1], LABEL_HEIGHT, 1);
    line.renderOrder = label.renderOrder = 2;
    line.visible = label.visible = false;
    this.world.add(line, label);
    return { line, label, canvas, text: null, colour: null };
  }

  // Points the camera at the parts from the front, above and to the right.
  fit() {
    const box = new THREE.Box3();
    for (const mesh of this.parts) if (mesh.visible) box.expandByObject(mesh);
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 0.05);
    const direction = new THREE.Vector3(0.6, -1.2, 0.8).normalize();
    this.camera.position.copy(centre).addScaledVector(direction, radius * 2.8);
    this.camera.near = radius / 100;
    this.camera.far = radius * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
  }

  // Marks a contact event at `point` (vas world) on part `partId` for a short while. The marker
  // is kept in the part's frame, so that it moves with the part; a point on no drawn part (the
  // hand's id, or a part not placed yet) stays where it is in the world.
  addMarker(point, begin, now, partId) {
    const geometry = new THREE.SphereGeometry(0.004, 12, 8);
    const colour = begin ? COLOURS.contactBegin : COLOURS.contactEnd;
    const material = new THREE.MeshBasicMaterial({ color: colour, transparent: true, depthTest: false });
    const marker = new THREE.Mesh(geometry, material);
    const part = this.parts[partId];
    const holder = part?.visible ? part : this.world;
    holder.updateMatrixWorld();
    marker.position.copy(holder.worldToLocal(this.world.localToWorld(new THREE.Vector3(...point))));
    marker.renderOrder = 1;
    Object.assign(marker.userData, { until: now + MARKER_MS, part: holder === part ? partId : null });
    holder.add(marker);
    this.markers.push(marker);
  }

  // Where `marker` is drawn, in the vas world.
  markerPosition(marker) {
    this.world.updateMatrixWorld();
    return this.world.worldToLocal(marker.getWorldPosition(new THREE.Vector3()));
  }

  // Draws one frame; `now` is the animation clock in milliseconds.
  render(now) {
    this.markers = this.markers.filter((marker) => {
      const left = marker.userData.until - now;
      if (left > 0) {
        marker.material.opacity = Math.min(1, left / 500);
        return true;
      }
      this.dispose(marker);
      return false;
    });
    if (!this.renderer.xr.isPresenting) this.controls.update();
    this.renderer.render(this.scene, this.camera);
  }

  // The pixel (CSS pixels from the canvas's top left) where the vas world point (x, y, z) is
  // drawn on the screen.
  project(x, y, z) {
    this.world.updateMatrixWorld();
    const point = this.world.localToWorld(new THREE.Vector3(x, y, z)).project(this.camera);
    const { clientWidth: width, clientHeight: height } = this.renderer.domElement;
    return [((point.x + 1) / 2) * width, ((1 - point.y) / 2) * height];
  }
}

// Writes `text` in `colour` on a dark rounded plate filling `canvas`.
function drawLabel(canvas, text, colour) {
  const context = canvas.getContext('2d');
  const { width, height } = canvas;
  context.clearRect(0, 0, width, height);
  context.fillStyle = 'rgba(20, 23, 27, 0.8)';
  context.beginPath();
  context.roundRect(0, 0, width, height, height / 4);
  context.fill();
  context.fillStyle = colour;
  context.font = `bold ${Math.round(height * 0.6)}px sans-serif`;
  context.textAlign = 'center';
  context.textBaseline = 'middle';
  context.fillText(text, width / 2, height / 2);
}

function place(mesh, position, rotation) {
  mesh.position.set(position[0], position[1], position[2]);
  mesh.quaternion.set(rotation[0], rotation[1], rotation[2], rotation[3]);
  mesh.visible = mesh.userData.hasGeometry;
}

// A BufferGeometry from a decoded mesh (see connection.js); normals computed when not sent.
function geometryOf(mesh) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
  geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
  if (mesh.normals) {
    geometry.setAttribute('normal', new THREE.BufferAttribute(mesh.normals, 3));
  } else {
    geometry.computeVertexNormals();
  }
  geometry.computeBoundingSphere();
  return geometry;
}
