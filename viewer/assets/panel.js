// The side panel: connection status, frame rate and latency, the controls, command answers and
// the events list.

// Events shown in the list; older ones are dropped from the page.
const MAX_EVENTS = 200;

export class Panel {
  // `send(command)` sends a command to the viewer; false when it could not.
  constructor(send) {
    this.send = send;
    this.element = (id) => document.getElementById(id);
    this.element('reset').onclick = () => this.command({ type: 'reset' });
    this.element('load').onclick = () => {
      const name = this.element('scenes').value;
      if (name) this.command({ type: 'load_scene', name });
    };
    this.element('metaphor').onchange = (change) =>
      this.command({ type: 'set_metaphor', metaphor: change.target.value });
  }

  command(command) {
    if (this.send(command)) {
      this.showReply(`${command.type.replace('_', ' ')}…`, false);
    } else {
      this.showReply('not connected to the viewer', true);
    }
  }

  showReply(text, isError) {
    const reply = this.element('reply');
    reply.textContent = text;
    reply.className = isError ? 'error' : '';
  }

  // The connection to the viewer (`open`) and whether a vas server answers it.
  showStatus(open, server) {
    const status = this.element('status');
    if (!open) {
      status.textContent = 'viewer not reachable; retrying…';
    } else if (!server) {
      status.textContent = 'no server';
    } else {
      status.textContent = 'connected';
    }
    status.className = open && server ? '' : 'warning';
  }

  showScene(name) {
    this.element('scene-name').textContent = name ? `scene: ${name}` : '';
  }

  // Fills the scene list, keeping the selection when it is still offered.
  showSceneNames(names) {
    const select = this.element('scenes');
    const selected = select.value;
    select.replaceChildren(...names.map((name) => new Option(name, name)));
    if (names.includes(selected)) select.value = selected;
    this.element('load').disabled = names.length === 0;
  }

  showPerf(fps, latencyMs) {
    const latency = latencyMs === null ? '–' : `${latencyMs.toFixed(1)} ms`;
    this.element('perf').textContent = `${fps.toFixed(0)} fps · latency ${latency}`;
  }

  addEvent(text) {
    const list = this.element('events');
    const item = document.createElement('li');
    item.textContent = text;
    list.prepend(item);
    while (list.children.length > MAX_EVENTS) list.lastElementChild.remove();
  }
}
