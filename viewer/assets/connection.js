// The page's side of its link to vas-viewer (link.js, a Web Worker, holds the WebSocket): hands
// each message to its handler and commands to the worker.

export class Connection {
  // `handlers` has one function per message type (status, event, reply, warning: each gets the
  // message and the wall-clock time it arrived), `scene(scene, meshes)`,
  // `frame(text, scene, arrivedMs, transport, superseded)` (see link.js) and `open(bool)` for the
  // connection itself.
  constructor(handlers) {
    this.handlers = handlers;
    this.worker = new Worker(new URL('./link.js', import.meta.url), { type: 'module' });
    this.worker.onmessage = ({ data }) => this.receive(data);
    this.open = false;
    this.handJointsDropped = 0;
  }

  // Sends a command; false when there is no connection to send it on.
  send(command) {
    if (!this.open) return false;
    this.worker.postMessage({ kind: 'command', command });
    return true;
  }

  // Sends a hand-joints message (an ArrayBuffer, see xr.js; handed over to the worker, so the
  // caller loses it); false when there is no connection to send it on. The worker drops it
  // rather than queue it behind a slow socket, and counts that in `handJointsDropped`.
  sendHandJoints(buffer) {
    if (!this.open) return false;
    this.worker.postMessage({ kind: 'hand_joints', buffer }, [buffer]);
    return true;
  }

  receive(data) {
    switch (data.kind) {
      case 'open':
        this.open = data.open;
        this.handlers.open(data.open);
        break;
      case 'scene':
        this.handlers.scene(data.scene, data.meshes);
        break;
      case 'hand_joints_dropped':
        this.handJointsDropped += 1;
        break;
      case 'frame':
        // Taken: the worker counts the frames the page has not taken yet.
        this.worker.postMessage({ kind: 'took' });
        this.handlers.frame(data.text, data.scene, data.arrivedMs, data.transport, data.superseded);
        break;
      case 'message': {
        const handler = this.handlers[data.message.type];
        if (handler) handler(data.message, data.arrivedMs);
        break;
      }
    }
  }
}
