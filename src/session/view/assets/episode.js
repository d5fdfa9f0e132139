// An episode's page (`coherent view TRANSCRIPT`), or two side by side
// (`coherent view A B`): the header, the scene at the chosen step, the step lines,
// and the chosen step in full. Keys: left/right a step, home/end the start and the
// last step; the address keeps the step (#step=12).

function header(ep, compact) {
  const h = ep.header;
  const r = ep.result;
  const gt = h.gt_steps === null ? 'no GT' : 'GT ' + h.gt_steps;
  const tokens = thousands(r.prompt_tokens) + ' prompt + ' + thousands(r.completion_tokens) +
    ' completion' + (r.cached_tokens ? ' (' + thousands(r.cached_tokens) + ' cached)' : '');
  const box = el('section', { class: 'card header' },
    el('h1', {}, h.task + (h.name ? ' · ' + h.name : '')),
    compact ? null : el('p', { class: 'instruction' }, h.instruction),
    el('div', { class: 'header-facts' },
      facts([
        ['method', h.method, 'method'],
        ['backend', h.backend, 'backend'],
        ['result', el('span', {}, badge(r.status), r.error ? ' ' + r.error : ''), 'result'],
        ['steps', r.steps + ' (' + gt + ', budget ' + h.max_steps + ')', 'steps'],
      ]),
      facts([
        ['LLM calls', String(r.llm_calls), 'calls'],
        ['tokens', tokens, 'tokens'],
        ['cost', r.cost_usd === null ? 'no price for this model' : usd(r.cost_usd), 'cost'],
        ['wall time', number(r.wall_ms / 1000, 2) + ' s', 'wall'],
      ]),
      facts([
        ['execution', h.execution === 'parallel' ? 'parallel: joint steps, each robot at most one action a step' : null, 'execution'],
        ['physics', h.physics ? 'every action also in Rapier' : null, 'physics'],
        ['robots', h.ros2 ? 'over ROS 2' : null, 'ros2'],
        ['seed', h.seed === null ? null : String(h.seed), 'seed'],
        ['temperature', h.temperature === null ? null : String(h.temperature), 'temperature'],
        ['history', String(h.history) + ' rounds', 'history'],
        ['prompts', h.prompts, 'prompts'],
        ['coherent', h.coherent, 'coherent'],
      ]),
    ));
  return box;
}

// The scene: the picture of the doors and lids as they are, the paths walked so far,
// each robot where it is, and below, where each one is and what it holds by the rules.
function scene(ep, ids) {
  const s = ep.scene;
  const host = el('div', { class: 'picture' });
  const list = el('ul', { class: 'robots' });
  const note = el('p', { class: 'muted physics-step' });
  const box = el('section', { class: 'card scene', 'data-episode': ids },
    host,
    s.warning ? el('p', { class: 'warning' }, s.warning) : null,
    note, list);
  let shownPicture = -1;
  let svg = null;
  const names = new Map(s.robots.map((r) => [r.id, r]));
  function show(k) {
    const m = s.moments[Math.min(k, s.moments.length - 1)];
    if (m.picture !== shownPicture && document.getElementById(ids + 'picture-' + m.picture)) {
      const template = document.getElementById(ids + 'picture-' + m.picture);
      svg = template.content.firstElementChild.cloneNode(true);
      host.replaceChildren(svg);
      shownPicture = m.picture;
    }
    if (svg) {
      const old = svg.querySelector('g.moving');
      if (old) old.remove();
      svg.append(movers(m));
    }
    list.replaceChildren(...m.robots.map((r) => {
      const mark = names.get(r.id);
      return el('li', { 'data-robot': r.id, 'data-room': r.room === null ? null : r.room },
        swatch(mark.colour),
        el('b', {}, mark.name), ' ', r.place || 'nowhere by the rules',
        r.holds.length ? el('span', { class: 'holds' }, '; holds ' + r.holds.join(', ')) : null);
    }));
    note.textContent = m.sim_seconds === null ? '' :
      'physics: the action took ' + number(m.sim_seconds, 2) + ' s of simulated time';
  }
  function movers(m) {
    const g = svgEl('g', { class: 'moving' });
    for (const t of s.tracks) {
      const at = m.robots.find((r) => r.id === t.id);
      const walked = Math.min(at ? at.walked : 1, t.points.length);
      const colour = names.get(t.id).colour;
      if (walked >= 2) {
        g.append(svgEl('polyline', {
          class: 'path', 'data-robot': t.id, fill: 'none', stroke: colour, 'stroke-width': 3,
          'stroke-opacity': 0.85, 'stroke-linejoin': 'round', 'marker-end': 'url(#arrow)',
          points: t.points.slice(0, walked).map((p) => p[0] + ',' + p[1]).join(' '),
        }));
      }
      if (t.points.length) {
        g.append(svgEl('circle', { cx: t.points[0][0], cy: t.points[0][1], r: 5, fill: colour }));
      }
    }
    for (const r of m.robots) {
      if (!r.at) continue;
      const mark = names.get(r.id);
      const [x, y] = r.at;
      g.append(svgEl('use', {
        class: 'robot', href: '#' + ids + 'robot-' + r.id, 'data-robot': r.id,
        'data-x': x, 'data-y': y, transform: 'translate(' + x + ' ' + y + ')',
      }));
      const label = svgEl('text', {
        x: x + 16, y: y - 14, 'font-size': 15, 'font-weight': 'bold', fill: mark.colour,
        stroke: '#ffffff', 'stroke-width': 4, 'paint-order': 'stroke', class: 'robot-label',
      }, mark.name);
      if (r.holds.length) {
        label.append(svgEl('tspan', { x: x + 16, dy: 17, 'font-weight': 'normal' }, 'holds ' + r.holds.join(', ')));
      }
      g.append(label);
    }
    return g;
  }
  return { element: box, show };
}

function swatch(colour) {
  const box = svgEl('svg', { width: 10, height: 10, class: 'swatch' }, svgEl('rect', { width: 10, height: 10, rx: 2, fill: colour }));
  return box;
}

// The chosen step in full.
function detail(ep) {
  const box = el('section', { class: 'card detail' });
  function show(k) {
    if (k === 0) {
      box.replaceChildren(el('h2', {}, 'Start'), el('p', { class: 'muted' },
        'The scene before the first step. ' + ep.steps.length + ' steps follow.'),
      ep.reference ? facts([['optimum', optimum(ep.reference.start), 'start-optimum']]) : null);
      return;
    }
    if (k > ep.steps.length) {
      box.replaceChildren(el('h2', {}, 'Step ' + k),
        el('p', { class: 'muted' }, 'This episode ended after ' + ep.steps.length + ' steps.'));
      return;
    }
    const st = ep.steps[k - 1];
    const parts = [el('h2', {}, 'Step ' + st.step + ' ', badge(st.status))];
    for (const e of st.events || []) parts.push(happened(e, 'Before this step'));
    parts.push(el('pre', { class: 'line' }, st.line));
    for (const e of st.robots) parts.push(entry(e));
    if (st.calls.length) {
      parts.push(el('h3', {}, 'Model calls (' + st.calls.length + ')'));
      st.calls.forEach((c) => parts.push(call(c)));
    }
    parts.push(el('p', { class: 'muted' }, 'round wall time ' + number(st.wall_ms, 0) + ' ms'));
    if (k === ep.steps.length && ep.reference) {
      for (const e of ep.reference.closing) parts.push(happened(e, 'After this step'));
    }
    box.replaceChildren(...parts);
  }
  return { element: box, show };
}

function entry(e) {
  const d = e.decision;
  const outcome = e.reason
    ? el('span', { class: 'refusal', 'data-reason': e.reason }, e.outcome)
    : el('span', {}, e.outcome);
  return el('div', { class: 'entry', 'data-robot': e.robot === null ? null : e.robot },
    el('h3', {}, e.name),
    facts([
      ['subtask', e.subtask, 'subtask'],
      ['reasoning', e.reasoning, 'reasoning'],
      ['decision', d ? (d.action === null ? 'no action' : d.action) +
        (d.can_do ? '' : ' (cannot do it now)') + (d.subtask_complete ? ' (finishes the subtask)' : '') : null, 'decision'],
      ['note', d && d.note ? d.note : null, 'note'],
      ['method', e.external, 'external'],
      ['outcome', outcome, 'outcome'],
      ['robot said', e.report, 'report'],
      ['feedback', e.feedback, 'feedback'],
    ]),
    e.actions.length ? folded('action list (' + e.actions.length + ')', e.actions.join('\n')) : null);
}

// An optimum as proven: steps (and joint steps), or why there is none.
function optimum(p) {
  if (p.unreachable !== null) return 'unreachable: ' + p.unreachable;
  if (p.steps !== null) {
    return p.steps + (p.steps === 1 ? ' step' : ' steps') +
      (p.makespan !== null ? ', ' + p.makespan + ' joint' : '');
  }
  return p.unknown !== null ? 'unknown: ' + p.unknown : 'unknown';
}

// The mark of an event, or of the end of its span.
function eventBadge(e) {
  return e.ended ? badge(e.kind + ' ends', 'ended') : badge(e.kind, 'event');
}

// An event that happened (or the end of its span), in full.
function happened(e, when) {
  return el('div', { class: 'happened' + (e.ended ? ' ended' : ''), 'data-event': e.event, 'data-kind': e.kind },
    el('h3', {}, when + ': ', eventBadge(e), ' events[' + e.event + ']'),
    facts([
      ['what', e.what, 'what'],
      ['told', e.told || 'nothing (failing actions are noticed as they fail)', 'told'],
      ['void', e.void, 'void'],
      ['optimum after it', optimum(e.optimum), 'optimum'],
    ]));
}

// An event's row in the step list: its mark, what it did, what the team was told, and
// the optimum from there; a link to the step it came before.
function eventRow(e, before, to) {
  return el('li', { class: 'event' + (e.ended ? ' ended' : ''), 'data-event': e.event, 'data-kind': e.kind, 'data-before': before },
    el('a', { href: '#step=' + to },
      eventBadge(e), ' ', e.what,
      e.told ? el('span', { class: 'told' }, 'told: ' + e.told) : null,
      e.void ? el('span', { class: 'void' }, 'changed nothing: ' + e.void) : null,
      el('span', { class: 'optimum', 'data-steps': e.optimum.steps === null ? null : e.optimum.steps }, 'optimum after it: ' + optimum(e.optimum))));
}

// What an episode with events is measured against, and how the team recovered.
function referenceCard(ep) {
  const ref = ep.reference;
  if (!ref) return el('section', { class: 'card reference' }, el('p', { class: 'muted' }, 'No events in this episode.'));
  const taken = ep.result.steps + ' taken';
  const steps = ref.steps !== null
    ? el('span', { 'data-reference': ref.steps, 'data-taken': ep.result.steps }, taken + ' against the reference\'s ' + ref.steps)
    : el('span', { 'data-taken': ep.result.steps }, taken + '; no reference' + (ref.unreachable === null ? ' (the optimum is unknown)' : ''));
  const rows = ref.recoveries.map((c) => el('tr', { 'data-event': c.event, class: c.ended ? 'ended' : null },
    el('td', {}, eventBadge(c), ' events[' + c.event + ']'), el('td', {}, String(c.step)),
    el('td', { 'data-key': 'rounds' }, c.rounds === null ? 'none' : String(c.rounds)),
    el('td', { 'data-key': 'wasted' }, String(c.wasted)), el('td', { 'data-key': 'calls' }, String(c.calls))));
  const table = rows.length
    ? el('table', { class: 'report recoveries' },
      el('thead', {}, el('tr', {}, ...['event', 'before step', 'rounds to recover', 'wasted actions', 'model calls'].map((h) => el('th', {}, h)))),
      el('tbody', {}, ...rows))
    : el('p', { class: 'muted' }, 'No event changed the world.');
  return el('section', { class: 'card reference' },
    el('h2', {}, 'Events and the reference'),
    el('div', { class: 'header-facts' },
      facts([
        ['steps', steps, 'reference'],
        ['out of reach', ref.unreachable === null ? null : 'for good: ' + ref.unreachable, 'unreachable'],
        ['at the start', 'optimum ' + optimum(ref.start), 'start'],
        ['events', ref.kinds.join(', '), 'kinds'],
      ]),
      el('div', {}, table)),
    el('p', { class: 'muted' }, 'The reference replans at each event, knowing nothing of those to come. ' +
      'A recovery lasts until an action first brings the goal nearer (none: not before the next event).'));
}

function call(c) {
  const parts = [el('summary', {}, c.role + (c.usage ? ' · ' + c.usage : '') + (c.error ? ' · failed' : ''))];
  for (const [role, content] of c.messages) {
    parts.push(el('div', { class: 'message-role' }, role), el('pre', { class: 'prompt' }, content));
  }
  if (c.answer !== null) parts.push(el('div', { class: 'message-role' }, 'answer'), el('pre', { class: 'answer' }, c.answer));
  if (c.error !== null) parts.push(el('div', { class: 'message-role' }, 'error'), el('pre', { class: 'error' }, c.error));
  return el('details', { class: 'call' }, ...parts);
}

// The step lines of one episode, a link each.
function stepList(ep) {
  const items = [el('li', { 'data-step': 0 }, el('a', { href: '#step=0' }, 'start'))];
  for (const st of ep.steps) {
    for (const e of st.events || []) items.push(eventRow(e, st.step, st.step));
    items.push(el('li', { class: st.status, 'data-step': st.step }, el('a', { href: '#step=' + st.step }, st.line)));
  }
  const closing = ep.reference ? ep.reference.closing : [];
  for (const e of closing) items.push(eventRow(e, ep.steps.length + 1, ep.steps.length));
  const ol = el('ol', {}, ...items);
  const box = el('section', { class: 'card steps' }, ol);
  function show(k) {
    for (const li of ol.children) {
      const here = Number(li.dataset.step) === k;
      li.classList.toggle('current', here);
      if (here) { li.setAttribute('aria-current', 'step'); li.scrollIntoView({ block: 'nearest' }); } else li.removeAttribute('aria-current');
    }
  }
  return { element: box, show };
}

// The step lines of two episodes, row by row, the first difference marked.
function lineTable(a, b, first) {
  const rows = [];
  const n = Math.max(a.steps.length, b.steps.length);
  const line = (ep, k) => (k === 0 ? 'start' : k <= ep.steps.length ? ep.steps[k - 1].line : '');
  for (let k = 0; k <= n; k++) {
    const events = (ep) => (k >= 1 && k <= ep.steps.length && ep.steps[k - 1].events) || [];
    const cell = (ep, cls) => el('td', { class: cls + (events(ep).length ? ' after-event' : ''), 'data-events': events(ep).length || null },
      events(ep).flatMap((e) => [eventBadge(e), ' ']), line(ep, k));
    const tr = el('tr', { 'data-step': k, class: k === first ? 'differs' : null },
      el('td', { class: 'n' }, el('a', { href: '#step=' + k }, String(k))),
      cell(a, 'a'), cell(b, 'b'));
    tr.addEventListener('click', () => go(k));
    rows.push(tr);
  }
  const table = el('table', { class: 'lines' }, el('tbody', {}, ...rows));
  const box = el('section', { class: 'card steps' }, table);
  function show(k) {
    for (const tr of rows) {
      const here = Number(tr.dataset.step) === k;
      tr.classList.toggle('current', here);
      if (here) tr.scrollIntoView({ block: 'nearest' });
    }
  }
  return { element: box, show };
}

let current = 0;
let last = 0;
const shows = [];

function go(k) {
  current = Math.max(0, Math.min(last, k));
  for (const show of shows) show(current);
  const hash = '#step=' + current;
  if (location.hash !== hash) {
    // A page opened from disk or shown in a frame may not rewrite its address.
    try { history.replaceState(null, '', hash); } catch (e) { /* the step still shows */ }
  }
  document.body.dataset.step = String(current);
}

function fromHash() {
  const m = /^#step=(\d+)$/.exec(location.hash);
  return m ? Number(m[1]) : null;
}

function keys() {
  document.addEventListener('keydown', (event) => {
    if (notForUs(event)) return;
    const to = { ArrowLeft: current - 1, ArrowRight: current + 1, Home: 0, End: last }[event.key];
    if (to === undefined) return;
    event.preventDefault();
    go(to);
  });
  window.addEventListener('hashchange', () => {
    const k = fromHash();
    if (k !== null && k !== current) go(k);
  });
}

const help = () => el('p', { class: 'keys' }, 'Keys: ', el('kbd', {}, '←'), ' ', el('kbd', {}, '→'),
  ' a step, ', el('kbd', {}, 'Home'), ' ', el('kbd', {}, 'End'), ' the start and the last step; each step is a link (#step=N).');

function episodePage(data) {
  const app = document.getElementById('app');
  if (data.kind === 'compare') {
    const [a, b] = data.episodes;
    const first = data.first_difference;
    const sa = scene(a, 'a-');
    const sb = scene(b, 'b-');
    const da = detail(a);
    const db = detail(b);
    const lines = lineTable(a, b, first);
    const jump = first === null
      ? el('p', { class: 'difference', id: 'first-difference' }, 'The two decide alike in every round.')
      : el('p', { class: 'difference', id: 'first-difference', 'data-step': first },
        'The decisions first differ in round ' + first + ': ', el('a', { href: '#step=' + first }, 'go there'));
    append(app, [el('div', { class: 'two' }, header(a, true), header(b, true)),
      a.reference || b.reference ? el('div', { class: 'two' }, referenceCard(a), referenceCard(b)) : null,
      jump, help(), lines.element,
      el('div', { class: 'two' }, sa.element, sb.element), el('div', { class: 'two' }, da.element, db.element)]);
    shows.push(lines.show, sa.show, sb.show, da.show, db.show);
    last = Math.max(a.steps.length, b.steps.length);
  } else {
    const ep = data.episodes[0];
    const sc = scene(ep, 'a-');
    const list = stepList(ep);
    const de = detail(ep);
    append(app, [header(ep, false), ep.reference ? referenceCard(ep) : null, help(),
      el('div', { class: 'layout' }, sc.element, el('div', {}, list.element, de.element))]);
    shows.push(sc.show, list.show, de.show);
    last = ep.steps.length;
  }
  keys();
  const k = fromHash();
  go(k === null ? 0 : k);
  drawn();
}

episodePage(readData());
