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

  // Fills the scene list and selects `current`, the name the server offers the scene it serves
  // under (null when it serves one it does not offer: then the selection is kept, if offered).
  showSceneNames(names, current) {
    const select = this.element('scenes');
    const selected = current ?? select.value;
    select.replaceChildren(...names.map((name) => new Option(name, name)));
    if (names.includes(selected)) select.value = selected;
    this.element('load').disabled = names.length === 0;
  }

  // Selects the sliding metaphor the server uses.
  showMetaphor(metaphor) {
    this.element('metaphor').value = metaphor;
  }

  // The sides whose hands have answered input so far (`right`, `left`).
  showHands(sides) {
    const hands = this.element('hands');
    hands.textContent = sides.length === 0 ? 'no hand seen yet' : `hands seen: ${sides.join(', ')}`;
    hands.className = sides.length === 0 ? 'warning' : '';
  }

  // The legend: a swatch per `palette` entry ({ css, words }: a CSS colour and what it means)
  // and one for the clearance pairs' colours, `clearance` (CSS colours from touching to the
  // threshold).
  showLegend(palette, clearance) {
    // A swatch and its words, kept on one line.
    const entry = (background, words) => {
      const swatch = document.createElement('span');
      swatch.className = 'swatch';
      swatch.style.background = background;
      const item = document.createElement('span');
      item.append(swatch, words);
      return item;
    };
    this.element('legend').replaceChildren(
      ...palette.map(({ css, words }) => entry(css, words)),
      entry(`linear-gradient(to right, ${clearance.join(', ')})`, 'clearance, touching to threshold'),
    );
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
