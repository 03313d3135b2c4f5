// "Enter VR": an immersive WebXR session drawing the same scene.
//
// WebXR's world has y up and its floor at y = 0; vas's has z up. While a session runs, the vas
// world group is turned a quarter turn about x (z to y) and set in front of the user at table
// height; when it ends the group is put back for the screen's camera.

import { VRButton } from 'three/addons/webxr/VRButton.js';

// Where vas's origin goes in the session's local-floor space: on a table in front of the user.
const TABLE = { height: 0.8, ahead: 0.4 };

export function setupXr(view, panel) {
  const { renderer, world } = view;
  renderer.xr.setReferenceSpaceType('local-floor');
  document.body.appendChild(VRButton.createButton(renderer));
  renderer.xr.addEventListener('sessionstart', () => {
    world.rotation.set(-Math.PI / 2, 0, 0);
    world.position.set(0, TABLE.height, -TABLE.ahead);
    panel.showReply('in VR', false);
  });
  renderer.xr.addEventListener('sessionend', () => {
    world.rotation.set(0, 0, 0);
    world.position.set(0, 0, 0);
    view.resize();
    panel.showReply('left VR', false);
  });
}
