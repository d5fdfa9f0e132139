// The index of a results file (`coherent view RESULTS -o DIR`, `coherent view --serve`):
// the report's tables as `coherent bench --report` computes them, success rate against
// cost and against steps drawn here, and every episode with a link to its page.
// Served, it asks its server every two seconds whether the file grew, and redraws.

const PALETTE = ['#1f6fd1', '#e07b00', '#2e9e44', '#d12f2f', '#8a2be2', '#8c564b', '#e377c2', '#17becf', '#7f7f7f', '#bcbd22'];

function stat(s, digits) {
  return number(s.mean, digits) + (s.ci95 === null ? '' : ' ± ' + number(s.ci95, digits));
}

// Table I or II: a row per method, `SR / AS` per column, then the ground truth.
function reportTable(t, id) {
  const head = el('tr', {}, el('th', {}, 'Method'),
    ...t.columns.map((c, j) => el('th', {}, c + ' (n=' + t.tasks[j] + ') SR / AS')));
  const rows = t.rows.map((row) => el('tr', { 'data-method': row.method }, el('td', {}, row.method),
    ...row.cells.map((cell, j) => (cell === null
      ? el('td', { 'data-column': t.columns[j] }, '-')
      : el('td', {
        'data-column': t.columns[j], 'data-sr': cell.sr.mean, 'data-as': cell.as.mean,
        'data-episodes': cell.episodes,
      }, stat(cell.sr, 3) + ' / ' + stat(cell.as, 1))))));
  rows.push(el('tr', { class: 'gt' }, el('td', {}, 'Ground truth'),
    ...t.gt.map((g, j) => el('td', { 'data-column': t.columns[j], 'data-as': g === null ? null : g }, '- / ' + number(g, 1)))));
  return el('section', {}, el('h2', {}, t.title),
    el('table', { class: 'report', id }, el('thead', {}, head), el('tbody', {}, ...rows)));
}

function costTable(costs) {
  const cols = [
    ['Episodes', 'episodes', (x) => String(x)], ['Steps', 'steps', (x) => String(x)],
    ['LLM calls / episode', 'calls_per_episode', (x) => number(x, 2)],
    ['Tokens / episode', 'tokens_per_episode', (x) => number(x, 0)],
    ['LLM calls / step', 'calls_per_step', (x) => number(x, 2)],
    ['Tokens / step', 'tokens_per_step', (x) => number(x, 0)],
    ['Cost / task', 'cost_per_task', usd], ['Cost / success', 'cost_per_success', usd],
  ];
  const head = el('tr', {}, el('th', {}, 'Method'), ...cols.map(([name]) => el('th', {}, name)));
  const rows = costs.map((c) => el('tr', { 'data-method': c.method }, el('td', {}, c.method),
    ...cols.map(([, key, show]) => el('td', { 'data-key': key, 'data-value': c[key] === null ? null : c[key] }, show(c[key])))));
  return el('section', {}, el('h2', {}, 'LLM calls, tokens and cost per method'),
    el('p', { class: 'muted' }, 'Cost in USD from each episode\'s cost_usd; - where a model has no price.'),
    el('table', { class: 'report', id: 'costs' }, el('thead', {}, head), el('tbody', {}, ...rows)));
}

// Ticks at 1, 2 or 5 times a power of ten over [lo, hi].
function ticks(lo, hi) {
  const span = hi - lo || 1;
  const raw = span / 5;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw);
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Number(v.toPrecision(12)));
  return out;
}

// A scatter of one point per method, success rate up the side.
function scatter(id, title, xLabel, points, format) {
  const W = 460, H = 320, L = 56, R = 20, T = 30, B = 46;
  const svg = svgEl('svg', { id, width: W, height: H, viewBox: '0 0 ' + W + ' ' + H, 'font-family': 'DejaVu Sans, sans-serif', 'font-size': 12 });
  svg.append(svgEl('text', { x: L, y: 18, 'font-weight': 'bold' }, title));
  if (!points.length) {
    svg.append(svgEl('text', { x: L, y: H / 2, fill: '#5b616b' }, 'nothing to draw'));
    return svg;
  }
  const xs = points.map((p) => p.x);
  let lo = Math.min(0, ...xs), hi = Math.max(...xs);
  if (hi === lo) hi = lo + 1;
  hi += (hi - lo) * 0.08;
  const px = (x) => L + (x - lo) / (hi - lo) * (W - L - R);
  const py = (y) => T + (1.05 - y) / 1.1 * (H - T - B);
  for (const v of ticks(lo, hi)) {
    svg.append(svgEl('line', { x1: px(v), x2: px(v), y1: T, y2: H - B, stroke: '#e6e8eb' }),
      svgEl('text', { x: px(v), y: H - B + 16, 'text-anchor': 'middle', fill: '#5b616b' }, format(v)));
  }
  for (const v of [0, 0.25, 0.5, 0.75, 1]) {
    svg.append(svgEl('line', { x1: L, x2: W - R, y1: py(v), y2: py(v), stroke: '#e6e8eb' }),
      svgEl('text', { x: L - 6, y: py(v) + 4, 'text-anchor': 'end', fill: '#5b616b' }, v.toFixed(2)));
  }
  svg.append(svgEl('line', { x1: L, x2: L, y1: T, y2: H - B, stroke: '#5b616b' }),
    svgEl('line', { x1: L, x2: W - R, y1: H - B, y2: H - B, stroke: '#5b616b' }),
    svgEl('text', { x: (L + W - R) / 2, y: H - 10, 'text-anchor': 'middle' }, xLabel),
    svgEl('text', { x: 14, y: (T + H - B) / 2, 'text-anchor': 'middle', transform: 'rotate(-90 14 ' + (T + H - B) / 2 + ')' }, 'success rate'));
  for (const p of points) {
    svg.append(svgEl('circle', { cx: px(p.x), cy: py(p.y), r: 6, fill: p.colour, 'data-method': p.label, 'data-x': p.x, 'data-y': p.y }),
      svgEl('text', { x: px(p.x) + 9, y: py(p.y) - 8, fill: p.colour }, p.label));
  }
  return svg;
}

// Success rate (Table I's average column) against cost per task and against steps.
function figures(report) {
  const t = report.table1;
  const avg = t.columns.length - 1;
  const colour = new Map(t.rows.map((r, i) => [r.method, PALETTE[i % PALETTE.length]]));
  const byMethod = new Map(report.costs.map((c) => [c.method, c]));
  const bySteps = [], byCost = [], unpriced = [];
  for (const row of t.rows) {
    const cell = row.cells[avg];
    if (!cell) continue;
    bySteps.push({ label: row.method, x: cell.as.mean, y: cell.sr.mean, colour: colour.get(row.method) });
    const c = byMethod.get(row.method);
    if (c && c.cost_per_task !== null) byCost.push({ label: row.method, x: c.cost_per_task, y: cell.sr.mean, colour: colour.get(row.method) });
    else unpriced.push(row.method);
  }
  return el('section', {}, el('h2', {}, 'Figures'),
    el('div', { class: 'figures' },
      el('div', { class: 'figure' }, scatter('sr-cost', 'Success rate against cost per task', 'cost per task (USD)', byCost, (v) => '$' + v.toPrecision(2)),
        unpriced.length ? el('p', { class: 'muted' }, 'No price, left out: ' + unpriced.join(', ')) : null),
      el('div', { class: 'figure' }, scatter('sr-steps', 'Success rate against steps', 'average steps (' + t.columns[avg] + ')', bySteps, (v) => String(v)))));
}

// One episode's row, built directly: a results file may have thousands.
function episodeRow(e, i, withReference) {
  const tr = document.createElement('tr');
  tr.dataset.line = i;
  tr.dataset.method = e.method;
  tr.dataset.scene = e.scene;
  tr.dataset.task = e.task_id;
  tr.dataset.seed = e.seed;
  const cell = (content, cls) => {
    const td = document.createElement('td');
    if (cls) td.className = cls;
    if (typeof content === 'string') td.textContent = content;
    else td.append(content);
    tr.append(td);
    return td;
  };
  cell(e.method);
  cell(e.scene);
  cell(String(e.task_id), 'num');
  cell(e.task_type || '-');
  cell(String(e.seed), 'num');
  const result = cell(badge(e.status));
  if (e.error) result.title = e.error;
  cell(String(e.steps), 'num');
  cell(e.gt_steps === null ? '-' : String(e.gt_steps), 'num');
  if (withReference) {
    const ref = e.reference;
    const td = cell(!ref ? '-' : ref.steps !== null ? String(ref.steps) : ref.unreachable !== null ? 'out of reach' : 'unknown', 'num reference');
    if (ref && ref.unreachable !== null) td.title = ref.unreachable;
    if (ref && ref.steps !== null) td.dataset.reference = ref.steps;
  }
  cell(String(e.max_steps), 'num');
  cell(String(e.llm_calls), 'num');
  cell(thousands(e.tokens), 'num');
  cell(usd(e.cost_usd), 'num');
  cell(e.link ? el('a', { href: e.link, class: 'episode-link' }, 'open') : '-');
  return tr;
}

// The episodes' table; its rows go in a few hundred at a time after the first, so that
// the tables above show at once.
function episodeTable(episodes) {
  // A column for the reference of episodes with events, only where some have one.
  const withReference = episodes.some((e) => e.reference);
  const names = ['method', 'scene', 'task', 'type', 'seed', 'result', 'steps', 'GT', 'budget', 'LLM calls', 'tokens', 'cost', 'page'];
  if (withReference) names.splice(8, 0, 'reference');
  const head = el('tr', {}, ...names.map((h) => el('th', { title: h === 'reference' ? 'the steps of an oracle that replans at each event (docs/dynamic.md)' : null }, h)));
  const body = el('tbody', {});
  const input = el('input', { type: 'search', placeholder: 'filter: method, scene, task, result', 'aria-label': 'filter the episodes' });
  const keep = (tr) => {
    const words = input.value.toLowerCase().split(/\s+/).filter(Boolean);
    const text = tr.textContent.toLowerCase();
    tr.hidden = !words.every((w) => text.includes(w));
  };
  input.addEventListener('input', () => { for (const tr of body.children) keep(tr); });
  const CHUNK = 400;
  const fill = (from) => {
    const end = Math.min(from + CHUNK, episodes.length);
    const part = document.createDocumentFragment();
    for (let i = from; i < end; i++) {
      const tr = episodeRow(episodes[i], i, withReference);
      if (input.value) keep(tr);
      part.append(tr);
    }
    body.append(part);
    if (end < episodes.length) setTimeout(() => fill(end), 0);
    else drawn();
  };
  fill(0);
  return el('section', {}, el('h2', {}, 'Episodes (' + episodes.length + ')'), el('div', { class: 'filter' }, input),
    el('table', { class: 'episodes', id: 'episodes' }, el('thead', {}, head), body));
}

function resultsPage(data) {
  const r = data.report;
  const app = document.getElementById('app');
  const backends = r.backends.length ? r.backends.join('; ') : 'none (no method here asks a model)';
  app.replaceChildren(
    el('section', { class: 'card' }, el('h1', {}, data.file.split('/').pop()),
      facts([
        ['results file', data.file, 'file'],
        ['episodes', String(data.episodes.length), 'episodes'],
        ['backend', backends, 'backend'],
        ['seeds', String(r.seeds.length) + (r.seeds.length > 1 ? ' (each cell: the mean over seeds ± the half-width of a 95% interval)' : ''), 'seeds'],
        ['left out', r.unfinished ? r.unfinished + ' episodes without a final result' + (r.errors ? ' (' + r.errors + ' raised an error)' : '') : null, 'unfinished'],
        ['untyped tasks', r.untyped_tasks ? r.untyped_tasks + ' (no plan: in Avg only)' : null, 'untyped'],
        ['live', data.live !== null ? el('span', { class: 'live' }, 'following the file as it grows') : null, 'live'],
      ])),
    reportTable(r.table1, 'table1'), reportTable(r.table2, 'table2'), costTable(r.costs),
    figures(r), episodeTable(data.episodes));
}

// Served: redraw when the file has grown.
function follow(version) {
  let shown = String(version);
  const tick = async () => {
    try {
      const now = await (await fetch('version', { cache: 'no-store' })).text();
      if (now !== shown) {
        const data = await (await fetch('results.json', { cache: 'no-store' })).json();
        resultsPage(data);
        shown = String(data.live);
      }
    } catch (e) {
      // The server is gone (the benchmark and its viewer ended): keep what is shown.
    }
  };
  setInterval(tick, 2000);
}

const RESULTS = readData();
resultsPage(RESULTS);
if (RESULTS.live !== null) follow(RESULTS.live);
