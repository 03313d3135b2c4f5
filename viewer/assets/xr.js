// "Enter VR": an immersive WebXR session drawing the same scene, and sending the user's tracked
// hands to the server where the browser offers hand tracking.
//
// WebXR's world has y up and its floor at y = 0; vas's has z up. While a session runs, the vas
// world group is turned a quarter turn about x (z to y) and set in front of the user at table
// height; when it ends the group is put back for the screen's camera.
//
// Hands: each XR frame, every input source with a `hand` has its 25 joints read in the session's
// reference space, taken into the vas world through the inverse of the world group's transform
// (so the server's hand is where the user's hand is in the drawn scene), and sent as one binary
// message per hand (layout below; vas-viewer publishes it on the server's hand-joints service).
// A hand with no poses this frame is sent with no joint valid, which the server reads as
// tracking lost; a hand that goes away (or a session that ends) is sent so once. The hands are
// the hands of one of the scene's users (`HandSender.user`, which main.js chooses); with none
// chosen, nothing is sent.

import * as THREE from 'three';
import { VRButton } from 'three/addons/webxr/VRButton.js';

// Where vas's origin goes in the session's local-floor space: on a table in front of the user.
const TABLE = { height: 0.8, ahead: 0.4 };

// WebXR's hand joints, in WebXR's order (OpenXR's without the palm).
const FINGER_JOINTS = ['metacarpal', 'phalanx-proximal', 'phalanx-intermediate', 'phalanx-distal', 'tip'];
export const JOINTS = [
  'wrist',
  'thumb-metacarpal', 'thumb-phalanx-proximal', 'thumb-phalanx-distal', 'thumb-tip',
  ...['index', 'middle', 'ring', 'pinky'].flatMap((finger) =>
    FINGER_JOINTS.map((joint) => `${finger}-finger-${joint}`)),
];

// The hand-joints message (viewer/src/hand_joints.rs), little-endian:
//   u32 kind = 1, u32 user (the scene's user index), u32 side (0 right, 1 left),
//   u32 valid (bit i: joint i has a pose),
//   f32 [25][8]: position x, y, z, orientation x, y, z, w, radius; metres, in the vas world.
// Binary because it is the cheap form at two hands and up to 120 frames a second: a fixed
// 816-byte buffer written in place, with no string built here and no JSON parsed in the viewer,
// and its length alone says it holds 25 joints.
const HAND_KIND = 1;
const SIDES = { right: 0, left: 1 };
const HEADER_BYTES = 16;
const JOINT_VALUES = 8;
const MESSAGE_BYTES = HEADER_BYTES + 4 * JOINT_VALUES * JOINTS.length;

export function setupXr(view, panel, connection) {
  const { renderer, world } = view;
  const hands = new HandSender(world, connection);
  renderer.xr.setReferenceSpaceType('local-floor');
  document.body.appendChild(VRButton.createButton(renderer, { optionalFeatures: ['hand-tracking'] }));
  renderer.xr.addEventListener('sessionstart', () => {
    world.rotation.set(-Math.PI / 2, 0, 0);
    world.position.set(0, TABLE.height, -TABLE.ahead);
    panel.showReply('in VR', false);
  });
  renderer.xr.addEventListener('sessionend', () => {
    hands.lost();
    world.rotation.set(0, 0, 0);
    world.position.set(0, 0, 0);
    view.resize();
    panel.showReply('left VR', false);
  });
  return {
    hands,
    // Called once per XR frame, before it is drawn.
    frame(xrFrame) {
      hands.send(xrFrame, renderer.xr.getReferenceSpace());
    },
  };
}

// Reads the tracked hands of each XR frame and sends them.
class HandSender {
  constructor(world, connection) {
    this.world = world;
    this.connection = connection;
    // The scene's user whose hands these are (an index into the scene's users), or null: none.
    this.user = 0;
    // Whether the last message sent for each side had a joint with a pose.
    this.tracked = { right: false, left: false };
    // Messages handed to the link, per side.
    this.posted = { right: 0, left: 0 };
    this.toVas = new THREE.Matrix4();
    this.toVasRotation = new THREE.Quaternion();
    this.position = new THREE.Vector3();
    this.rotation = new THREE.Quaternion();
    this.values = new Float32Array(JOINT_VALUES);
  }

  // Sends the hands as user `user`'s from now on (null: sends none), once the hands sent as
  // another's are sent untracked.
  setUser(user) {
    if (user === this.user) return;
    this.lost();
    this.user = user;
  }

  send(frame, referenceSpace) {
    if (!referenceSpace || this.user === null) return;
    // The world group places vas in the reference space; its inverse takes the joints back.
    this.world.updateMatrixWorld();
    this.toVas.copy(this.world.matrixWorld).invert();
    this.world.getWorldQuaternion(this.toVasRotation).invert();
    const seen = { right: false, left: false };
    for (const source of frame.session.inputSources) {
      const handedness = source.handedness;
      if (!source.hand || !(handedness in SIDES) || seen[handedness]) continue;
      seen[handedness] = true;
      this.post(handedness, this.read(frame, source.hand, referenceSpace, SIDES[handedness]));
    }
    for (const handedness of Object.keys(SIDES)) {
      if (!seen[handedness] && this.tracked[handedness]) {
        this.post(handedness, untracked(this.user, handedness));
      }
    }
  }

  // Every side last sent as tracked, sent as untracked (the session ends).
  lost() {
    for (const handedness of Object.keys(SIDES)) {
      if (this.tracked[handedness]) this.post(handedness, untracked(this.user, handedness));
    }
  }

  // One hand's message: its joints in the vas world; a joint without a pose, or with a value
  // that is not finite in single precision, is left out (its valid bit clear, its values 0).
  read(frame, hand, referenceSpace, side) {
    const buffer = new ArrayBuffer(MESSAGE_BYTES);
    const data = new DataView(buffer);
    const values = this.values;
    let valid = 0;
    JOINTS.forEach((name, index) => {
      const space = hand.get(name);
      const pose = space ? frame.getJointPose(space, referenceSpace) : null;
      if (!pose) return;
      const { position: p, orientation: o } = pose.transform;
      this.position.set(p.x, p.y, p.z).applyMatrix4(this.toVas);
      this.rotation.set(o.x, o.y, o.z, o.w).premultiply(this.toVasRotation);
      values[0] = this.position.x;
      values[1] = this.position.y;
      values[2] = this.position.z;
      values[3] = this.rotation.x;
      values[4] = this.rotation.y;
      values[5] = this.rotation.z;
      values[6] = this.rotation.w;
      values[7] = pose.radius ?? 0;
      if (!values.every(Number.isFinite)) return;
      const at = HEADER_BYTES + 4 * JOINT_VALUES * index;
      values.forEach((value, offset) => data.setFloat32(at + 4 * offset, value, true));
      valid |= 1 << index;
    });
    writeHeader(data, this.user, side, valid);
    return buffer;
  }

  post(handedness, buffer) {
    const valid = new DataView(buffer).getUint32(12, true);
    if (this.connection.sendHandJoints(buffer)) {
      this.tracked[handedness] = valid !== 0;
      this.posted[handedness] += 1;
    }
  }
}

// A message saying that `user`'s hand of `handedness` is not tracked: no joint has a pose.
function untracked(user, handedness) {
  const buffer = new ArrayBuffer(MESSAGE_BYTES);
  writeHeader(new DataView(buffer), user, SIDES[handedness], 0);
  return buffer;
}

function writeHeader(data, user, side, valid) {
  data.setUint32(0, HAND_KIND, true);
  data.setUint32(4, user, true);
  data.setUint32(8, side, true);
  data.setUint32(12, valid >>> 0, true);
}
