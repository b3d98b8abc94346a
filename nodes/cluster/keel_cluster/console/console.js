// Keel console: the page of `keel-cluster console` (keel_cluster/console.py).
//
// The server sends events, {i, t, n, f, a, k, d, p}: index, time (ns), node, fsm, action,
// kind, a sentence for the timeline, and a JSON merge patch (RFC 7386) of the state. The
// page keeps every event, sorted by time, and shows the run at a cursor: the state is the
// patches of the events up to the cursor, applied in time order (`foldTo`, the page's one
// fold). Following a live run, the cursor is the newest event; playing back, it moves at
// the chosen speed; seeking, it jumps (from the nearest snapshot of the state). What the
// page shows beyond the state is derived from it at the cursor (`derive`): the acting
// Master, the cluster's configuration and phase, which nodes fell silent.
"use strict";
(function () {
  const SEEN_EVERY_NS = 500e6; // console.py SEEN_EVERY_NS: a live node's mark is at most this old
  const SILENT_MARGIN_NS = 250e6;
  const SNAPSHOT_EVERY = 2000; // events between two snapshots of the state
  const LIST_MAX = 200; // rows of the event list
  const MARKERS_MAX = 4000; // timeline markers drawn at most: those nearest the cursor
  const INSERT_MAX = 64; // events arriving out of order put in place one by one; more: one sort
  const RENDER_MIN_MS = 100; // the state, the tables and the list: ten times a second at most
  const TIMELINE_MIN_MS = 250; // the timeline, the costliest to draw, while following a run
  const NS = 1e9;

  const $ = (id) => document.getElementById(id);
  let commandOffered = false;  // the page may command the run (see the command form below)
  const ESCAPES = { "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" };
  const esc = (text) => String(text).replace(/[&<>"']/g, (c) => ESCAPES[c]);
  // The server sends each field in its type (console.py FIELD_TYPES); the page draws only
  // what has the type it expects.
  const list = (value) => (Array.isArray(value) ? value : []);
  const isObject = (value) => typeof value === "object" && value !== null && !Array.isArray(value);

  // --- What arrived ------------------------------------------------------------------
  const events = []; // by index (arrival order)
  let byTime = []; // the same events sorted by (t, i)
  let mission = null;
  let status = null;
  let instance = null;

  // --- The fold ----------------------------------------------------------------------
  const emptyState = () => ({ nodes: {}, path: {}, measures: {}, faults: {} });
  let state = emptyState();
  let applied = 0; // byTime[0 .. applied) are in `state`
  let snapshots = []; // {at, state, lanes}: the state after byTime[0 .. at)
  let lanes = {}; // node -> [[t, key, at]]: its role over time, as applied (timeline)

  // RFC 7386: objects merge key by key, null removes a key, anything else replaces.
  function apply(target, patch) {
    for (const key of Object.keys(patch)) {
      const value = patch[key];
      if (value === null) {
        delete target[key];
      } else if (typeof value === "object" && !Array.isArray(value)) {
        if (typeof target[key] !== "object" || target[key] === null || Array.isArray(target[key])) {
          target[key] = {};
        }
        apply(target[key], value);
      } else {
        target[key] = value;
      }
    }
    return target;
  }

  const laneKey = (node) => (node.down ? "down" : node.role || "");

  function foldTo(t) {
    const end = upperBound(t);
    if (end < applied) restore(end);
    while (applied < end) {
      const event = byTime[applied];
      if (event.p) {
        apply(state, event.p);
        for (const name of Object.keys(event.p.nodes || {})) {
          const key = laneKey(state.nodes[name] || {});
          const lane = lanes[name] || (lanes[name] = []);
          if (!lane.length || lane[lane.length - 1][1] !== key) lane.push([event.t, key, applied]);
        }
      }
      applied += 1;
      if (applied % SNAPSHOT_EVERY === 0) {
        snapshots.push({ at: applied, state: structuredClone(state), lanes: structuredClone(lanes) });
      }
    }
  }

  // Back to the state before byTime[index] (events were inserted there, or the cursor
  // went back): the nearest snapshot at or before it.
  function restore(index) {
    while (snapshots.length && snapshots[snapshots.length - 1].at > index) snapshots.pop();
    const snapshot = snapshots[snapshots.length - 1];
    state = snapshot ? structuredClone(snapshot.state) : emptyState();
    lanes = snapshot ? structuredClone(snapshot.lanes) : {};
    applied = snapshot ? snapshot.at : 0;
  }

  // The first event after t; lowerBound: the first at or after it.
  function lowerBound(t) {
    let low = 0;
    let high = byTime.length;
    while (low < high) {
      const middle = (low + high) >> 1;
      if (byTime[middle].t < t) low = middle + 1;
      else high = middle;
    }
    return low;
  }

  function upperBound(t) {
    let low = 0;
    let high = byTime.length;
    while (low < high) {
      const middle = (low + high) >> 1;
      if (byTime[middle].t <= t) low = middle + 1;
      else high = middle;
    }
    return low;
  }

  // Whether event a comes before event b in byTime: by time, then by index.
  const before = (a, b) => a.t < b.t || (a.t === b.t && a.i < b.i);

  // Where an event goes in byTime: after every event that comes before it.
  function insertionPoint(event) {
    let low = 0;
    let high = byTime.length;
    while (low < high) {
      const middle = (low + high) >> 1;
      if (before(event, byTime[middle])) high = middle;
      else low = middle + 1;
    }
    return low;
  }

  function receive(batch) {
    if (!batch.length) return;
    const late = []; // events that come before the newest one: lines of another node that arrived later
    for (const event of batch) {
      events[event.i] = event;
      const newest = byTime[byTime.length - 1];
      if (!newest || !before(event, newest)) byTime.push(event);
      else late.push(event);
    }
    if (!late.length) return;
    // Into their place (a few by binary search, many by one sort), and the state from
    // there applied again.
    let earliest = Infinity;
    for (const event of late) earliest = Math.min(earliest, event.t);
    if (late.length <= INSERT_MAX) {
      for (const event of late) byTime.splice(insertionPoint(event), 0, event);
    } else {
      for (const event of late) byTime.push(event);
      byTime.sort((a, b) => a.t - b.t || a.i - b.i);
    }
    listOutOfOrder = true;
    const from = lowerBound(earliest);
    if (from < applied) restore(from);
  }

  // --- Time and the cursor -------------------------------------------------------------
  let following = true; // the cursor is the newest event
  let cursor = 0; // ns, when not following
  let playing = false;
  let speed = 1;
  let pendingSeek = null; // seconds from the start, from the address (#t=...)
  let pendingPlay = false;

  const firstT = () => (byTime.length ? byTime[0].t : 0);
  const lastT = () => (byTime.length ? byTime[byTime.length - 1].t : 0);
  const now = () => (following ? lastT() : cursor);
  const seconds = (t) => (t - firstT()) / NS;
  const wallClock = (t) => t > 1e17; // keel-node's t_ns is wall-clock time, keel-sim's starts at 0

  function seek(t, keepPlaying) {
    following = false;
    cursor = Math.max(firstT(), Math.min(lastT(), t));
    if (!keepPlaying) playing = false;
    remember();
    redrawTimeline();
  }

  function follow() {
    following = true;
    playing = false;
    history.replaceState(null, "", location.pathname + location.search);
    redrawTimeline();
  }

  function remember() {
    if (!following) {
      history.replaceState(null, "", `#t=${seconds(cursor).toFixed(3)}${playing ? "&play" : ""}`);
    }
  }

  function readAddress() {
    const hash = new URLSearchParams(location.hash.slice(1));
    if (hash.has("t")) {
      const value = Number(hash.get("t"));
      if (Number.isFinite(value)) pendingSeek = value;
    }
    pendingPlay = hash.has("play");
    if (pendingPlay && pendingSeek === null) pendingSeek = 0;
  }

  let frame = 0;
  function play() {
    if (following || cursor >= lastT()) {
      following = false;
      cursor = firstT();
    }
    playing = true;
    frame = performance.now();
    remember();
    requestAnimationFrame(advance);
    scheduleRender();
  }

  function advance(when) {
    if (!playing) return;
    cursor += (when - frame) * 1e6 * speed;
    frame = when;
    if (cursor >= lastT()) {
      cursor = lastT();
      playing = false;
      // A live run's replay that catches up follows it again.
      if (status && !status.finished) following = true;
      remember();
    } else {
      requestAnimationFrame(advance);
    }
    scheduleRender();
  }

  // --- What the page derives from the state --------------------------------------------
  function phaseOf(config) {
    if (config === "SAFE") return "safe mode";
    for (const phase of mission ? mission.phases : []) {
      if (phase.configurations.some((c) => c.name === config)) return phase.name;
    }
    return "";
  }

  function nodeNames(nodes) {
    const names = mission ? mission.nodes.map((n) => n.name) : [];
    for (const name of Object.keys(nodes).sort()) if (!names.includes(name)) names.push(name);
    return names;
  }

  function derive(at) {
    const period = mission ? mission.period_ms * 1e6 : 0;
    const silentAfter = (mission ? period * Math.max(1, mission.miss_limit) : NS) + SEEN_EVERY_NS + SILENT_MARGIN_NS;
    const nodes = nodeNames(state.nodes).map((name) => {
      const node = state.nodes[name] || {};
      const silentFor = node.seen === undefined ? null : at - node.seen;
      let condition = "up";
      if (node.seen === undefined && !node.down) condition = "unheard";
      else if (node.down) condition = "down";
      else if (node.paused) condition = "paused";
      else if (silentFor > silentAfter) condition = "silent";
      return Object.assign({ name, condition, silentFor }, node);
    });
    const masters = nodes
      .filter((n) => n.role === "Master" && n.condition === "up" && !n.resigned)
      .sort((a, b) => (b.epoch || 0) - (a.epoch || 0));
    const master = masters[0] || null;
    const config = master ? master.masterConfig || master.config || null : null;
    const path = Object.keys(state.path)
      .map((k) => state.path[k])
      .sort((a, b) => a.t - b.t);
    return { nodes, master, config, phase: config ? phaseOf(config) : "", path };
  }

  // --- Rendering -----------------------------------------------------------------------
  let renderQueued = false;
  let lastRender = 0;
  let lastTimeline = 0;
  let timelineWanted = true; // the user moved the cursor or changed the view: draw it now
  let timelineTimer = null;
  function scheduleRender() {
    if (renderQueued) return;
    renderQueued = true;
    setTimeout(() => {
      renderQueued = false;
      lastRender = performance.now();
      render();
    }, Math.max(0, RENDER_MIN_MS - (performance.now() - lastRender)));
  }

  function redrawTimeline() {
    timelineWanted = true;
    scheduleRender();
  }

  function render() {
    if (pendingSeek !== null && byTime.length) {
      const target = firstT() + pendingSeek * NS;
      pendingSeek = null;
      seek(target, false);
      if (pendingPlay) {
        pendingPlay = false;
        playing = true;
        frame = performance.now();
        requestAnimationFrame(advance);
      }
    }
    const at = now();
    foldTo(at);
    const view = derive(at);
    renderNotice();
    renderControls(at);
    renderSummary(view);
    renderNodes(view);
    renderGraph(view);
    renderLinks(view);
    renderMeasures();
    renderEvents(at);
    // Following a live run, the timeline is drawn a few times a second; a move of the
    // cursor by the user, or a frame of a playback, draws it at once.
    const since = performance.now() - lastTimeline;
    if (timelineWanted || playing || since >= TIMELINE_MIN_MS) {
      timelineWanted = false;
      lastTimeline = performance.now();
      renderTimeline(at);
    } else if (timelineTimer === null) {
      timelineTimer = setTimeout(() => {
        timelineTimer = null;
        redrawTimeline();
      }, TIMELINE_MIN_MS - since);
    }
  }

  function time(t) {
    return `${seconds(t) >= 0 ? "+" : ""}${seconds(t).toFixed(3)} s`;
  }

  function renderNotice() {
    const notes = [];
    if (status && !status.exists) notes.push(`${status.run_dir} does not exist (yet): waiting for it.`);
    else if (status && status.waiting) notes.push(`Waiting for traces: no *.trace.ndjson in ${status.run_dir} yet.`);
    if (status && status.mission_error) notes.push(status.mission_error);
    else if (status && !mission && !status.waiting) {
      notes.push("No mission image in the run directory: the graph is not drawn (keel-cluster console --mission FILE).");
    }
    if (status && status.error) {
      notes.push(`The console failed to read the run ${status.errors} time(s) (the last: ${status.error}): lines may be missing.`);
    }
    if (status && status.dropped) {
      notes.push(`${status.dropped} checkpoints and liveness marks past the console's limit are not listed (what they changed is shown).`);
    }
    if (status && status.truncated) notes.push("The run is longer than the console keeps: later lines are not shown.");
    const notice = $("notice");
    if (notice.hidden !== !notes.length) notice.hidden = !notes.length;
    setText(notice, notes.join(" "));
  }

  function renderControls(at) {
    setText($("play"), playing ? "Pause" : "Play");
    if ($("play").classList.contains("on") !== playing) $("play").classList.toggle("on");
    if ($("live").classList.contains("on") !== following) $("live").classList.toggle("on");
    setText($("live"), status && status.finished ? "End" : "Live");
    // A finished run takes no more commands.
    const commandHidden = !commandOffered || Boolean(status && status.finished);
    if ($("command").hidden !== commandHidden) $("command").hidden = commandHidden;
    const span = lastT() - firstT();
    if (document.activeElement !== $("seek")) {
      const value = String(span > 0 ? Math.round(((at - firstT()) / span) * 1000) : 1000);
      if ($("seek").value !== value) $("seek").value = value;
    }
    let text = byTime.length ? `t = ${time(at)}` : "t = -";
    if (byTime.length && wallClock(at)) text += `  ${new Date(at / 1e6).toISOString().slice(11, 23)} UTC`;
    setText($("clock"), text);
  }

  function renderSummary(view) {
    setText($("current-master"), view.master ? view.master.name : "none");
    setText($("current-config"), view.config || "-");
    setText($("current-phase"), view.phase || "-");
    setText($("current-epoch"), view.master ? view.master.epoch : "-");
    const down = view.nodes.filter((n) => n.condition === "down" || n.condition === "silent").length;
    setText($("node-count"), `${view.nodes.length} nodes${down ? `, ${down} down or silent` : ""}`);
  }

  function renderNodes(view) {
    const kinds = {};
    for (const node of mission ? mission.nodes : []) kinds[node.name] = node.role || node.kind;
    const rows = view.nodes.map((n) => {
      // A node down or silent runs nothing we know of: its last tasks, struck through.
      const stopped = n.held || (n.condition !== "up" && n.condition !== "unheard");
      // Its data rates, from its status lines' counts (run --console): executions, samples
      // in and out per second over the last second or so.
      const rates = n.rates && typeof n.rates === "object" ? n.rates : {};
      const tasks = list(n.active)
        .map((t) => {
          const r = rates[t];
          const rate = r && !stopped ? ` <span class="rate">${esc(r.exec)}/s</span>` : "";
          const title = r ? ` title="${esc(`executions ${r.exec}/s, samples in ${r.in}/s, out ${r.out}/s`)}"` : "";
          return `<span class="task${stopped ? " held" : ""}"${title}>${esc(t)}${rate}</span>`;
        })
        .join("");
      let condition = n.condition;
      if (condition === "silent") condition = `silent ${(n.silentFor / NS).toFixed(1)} s`;
      const flags = [];
      if (n.resigned) flags.push("resigned");
      if (n.held) flags.push("held (no lease)");
      if (n.late) flags.push("late tick");
      const config = n.config === undefined ? "-" : n.config;
      return `<tr id="node-${esc(n.name)}" class="${esc(n.role || "")} ${esc(n.condition)}">` +
        `<td>${esc(n.name)}<span class="tag">${esc(kinds[n.name] || "")}</span></td>` +
        `<td class="role">${esc(n.role || "-")}</td><td class="epoch">${esc(n.epoch === undefined ? "-" : n.epoch)}</td>` +
        `<td class="config">${esc(config)}</td><td class="phase">${esc(phaseOf(n.config) || "-")}</td>` +
        `<td class="stage">${esc(n.stage || "-")}</td><td class="tasks">${tasks}</td>` +
        `<td class="state">${esc(condition)}${flags.length ? ` <span class="problem">${esc(flags.join(", "))}</span>` : ""}</td></tr>`;
    });
    setHtml($("nodes").tBodies[0], rows.join(""));
  }

  // Replace an element's content, or an attribute, only when it changed: the browser lays
  // out and paints again what a write touches, even when it writes the same.
  function setText(element, text) {
    if (element.textContent !== String(text)) element.textContent = text;
  }

  function setAttribute(element, name, value) {
    if (element.getAttribute(name) !== String(value)) element.setAttribute(name, value);
  }

  function setHtml(element, html) {
    if (element.__html !== html) {
      element.innerHTML = html;
      element.__html = html;
    }
  }

  // --- The graph -----------------------------------------------------------------------
  let graphFor = null;
  let layout = null;

  function layoutGraph() {
    const column = 96;
    const row = 40;
    const left = 70;
    const pos = {};
    const bands = [];
    let top = 8;
    let deepest = 0;
    for (const phase of mission.phases) {
      const names = phase.configurations.map((c) => c.name);
      const depth = { [phase.initial]: 0 };
      const queue = [phase.initial];
      while (queue.length) {
        const from = queue.shift();
        for (const edge of mission.edges) {
          if (edge.from === from && edge.kind !== "phase" && names.includes(edge.to) && !(edge.to in depth)) {
            depth[edge.to] = depth[from] + 1;
            queue.push(edge.to);
          }
        }
      }
      const columns = [];
      for (const name of names) {
        const d = name in depth ? depth[name] : Math.max(0, ...Object.values(depth)) + 1;
        (columns[d] = columns[d] || []).push(name);
      }
      let rows = 1;
      columns.forEach((names, d) => {
        rows = Math.max(rows, names.length);
        deepest = Math.max(deepest, d);
        names.forEach((name, k) => {
          pos[name] = { x: left + d * column, y: top + 22 + k * row };
        });
      });
      bands.push({ name: phase.name, y: top + 10 });
      top += 22 + rows * row + 10;
    }
    // Safe mode, where any failure the graph has no edge for leads: right of every phase.
    pos.SAFE = { x: left + (deepest + 1) * column, y: Math.max(30, (top - 10) / 2) };
    const width = left + (deepest + 1) * column + 60;
    return { pos, bands, width, height: Math.max(top, pos.SAFE.y + 30) };
  }

  // Where the segment from box a's centre towards b's leaves a's box (half sizes w, h).
  function boxExit(a, b, w, h) {
    const dx = b.x - a.x;
    const dy = b.y - a.y;
    if (!dx && !dy) return { x: a.x, y: a.y };
    const scale = Math.min(dx ? w / Math.abs(dx) : Infinity, dy ? h / Math.abs(dy) : Infinity);
    return { x: a.x + dx * scale, y: a.y + dy * scale };
  }

  function edgePath(from, to, bend) {
    const a = boxExit(from, to, 34, 15);
    const b = boxExit(to, from, 34, 15);
    const mx = (a.x + b.x) / 2 - (b.y - a.y) * bend;
    const my = (a.y + b.y) / 2 + (b.x - a.x) * bend;
    return { d: `M${a.x.toFixed(1)},${a.y.toFixed(1)} Q${mx.toFixed(1)},${my.toFixed(1)} ${b.x.toFixed(1)},${b.y.toFixed(1)}`, mx, my };
  }

  function drawGraph() {
    const svg = $("graph");
    if (!mission) {
      svg.innerHTML = "";
      svg.setAttribute("height", 20);
      return;
    }
    layout = layoutGraph();
    const parts = [
      '<defs><marker id="arrow" viewBox="0 0 8 8" refX="7" refY="4" markerWidth="7" markerHeight="7" orient="auto">' +
        '<path d="M0,0 L8,4 L0,8 z" fill="#9aa5ae"/></marker>' +
        '<marker id="arrow-taken" viewBox="0 0 8 8" refX="7" refY="4" markerWidth="6" markerHeight="6" orient="auto">' +
        '<path d="M0,0 L8,4 L0,8 z" fill="#f08c00"/></marker></defs>',
    ];
    for (const band of layout.bands) parts.push(`<text class="band" x="4" y="${band.y}">${esc(band.name)}</text>`);
    mission.edges.forEach((edge, k) => {
      const from = layout.pos[edge.from];
      const to = layout.pos[edge.to];
      if (!from || !to) return;
      const path = edgePath(from, to, edge.kind === "phase" ? 0.12 : 0.04);
      parts.push(`<path class="edge ${esc(edge.kind)}" data-k="${k}" d="${path.d}" marker-end="url(#arrow)">` +
        `<title>${esc(`${edge.from} -> ${edge.to}: ${edge.kind} ${edge.label}`)}</title></path>`);
      // Phase edges map every configuration of a phase to one of the next: drawn faintly,
      // named in their tooltip; failure and recovery edges name their node.
      if (edge.kind !== "phase" && mission.edges.length <= 60) {
        parts.push(`<text class="edge-label" x="${path.mx.toFixed(1)}" y="${(path.my - 2).toFixed(1)}">${esc(edge.label)}</text>`);
      }
    });
    const masters = {};
    for (const phase of mission.phases) for (const c of phase.configurations) masters[c.name] = c.master;
    for (const [name, p] of Object.entries(layout.pos)) {
      parts.push(`<g class="config" data-c="${esc(name)}" transform="translate(${p.x},${p.y})">` +
        `<rect x="-34" y="-15" width="68" height="30" rx="6"/>` +
        `<text y="${masters[name] ? -1 : 4}">${esc(name)}</text>` +
        (masters[name] ? `<text class="sub" y="11">${esc(masters[name])}</text>` : "") + "</g>");
    }
    parts.push('<g id="graph-path"></g>');
    svg.innerHTML = parts.join("");
    svg.setAttribute("viewBox", `0 0 ${layout.width} ${layout.height}`);
    svg.setAttribute("height", Math.min(520, layout.height));
    graphFor = mission;
  }

  function renderGraph(view) {
    if (graphFor !== mission) drawGraph();
    if (!mission) {
      $("path").textContent = "";
      return;
    }
    const svg = $("graph");
    const visited = new Set(view.path.map((s) => s.c));
    for (const g of svg.querySelectorAll("g.config")) {
      if (g.classList.contains("current") !== (g.dataset.c === view.config)) g.classList.toggle("current");
      if (g.classList.contains("visited") !== visited.has(g.dataset.c)) g.classList.toggle("visited");
    }
    const taken = new Set();
    const jumps = [];
    const steps = [];
    view.path.forEach((step, k) => {
      const p = layout.pos[step.c];
      if (p) steps.push(`<text class="step" x="${p.x + 30}" y="${p.y - 17}">${k + 1}</text>`);
      if (!k) return;
      const from = view.path[k - 1].c;
      const index = mission.edges.findIndex((e) => e.from === from && e.to === step.c);
      if (index >= 0) taken.add(String(index));
      else if (layout.pos[from] && p) jumps.push(edgePath(layout.pos[from], p, 0.25).d);
    });
    for (const edge of svg.querySelectorAll("path.edge")) {
      const on = taken.has(edge.dataset.k);
      if (edge.classList.contains("taken") !== on) edge.classList.toggle("taken", on);
      setAttribute(edge, "marker-end", on ? "url(#arrow-taken)" : "url(#arrow)");
    }
    setHtml($("graph-path"), steps.join("") +
      jumps.map((d) => `<path class="jump" d="${d}" marker-end="url(#arrow-taken)"><title>a switch with no edge of its own (a take-over or the ground's)</title></path>`).join(""));
    setText($("path"), view.path.length
      ? "path: " + view.path.map((s) => `${s.c} (${time(s.t)}, ${s.m})`).join(" \u2192 ")
      : "path: no switch completed yet");
  }

  // --- Heartbeat links -----------------------------------------------------------------
  function renderLinks(view) {
    const limit = mission ? mission.miss_limit : 0;
    const names = view.nodes.map((n) => n.name);
    const monitors = view.nodes.filter((n) => isObject(n.missed) && Object.keys(n.missed).length);
    if (!monitors.length) {
      setHtml($("links"), '<tr><td class="muted">no monitor has counted a period yet</td></tr>');
      return;
    }
    const head = `<tr><th>monitor \\ node</th>${names.map((n) => `<th>${esc(n)}</th>`).join("")}</tr>`;
    const rows = monitors.map((m) => {
      const cells = names.map((name) => {
        if (name === m.name) return "<td>\u00b7</td>";
        if (!(name in m.missed)) return '<td class="muted"></td>';
        const missed = m.missed[name];
        const declared = list(m.declared).includes(name);
        const suspected = list(m.suspects).includes(name);
        const cls = declared ? "declared" : missed > 0 ? "missing" : "ok";
        const text = declared ? "\u2715" : String(missed);
        const title = `${m.name} -> ${name}: ${missed} period(s) missed${limit ? ` of ${limit}` : ""}` +
          `${declared ? ", declared failed" : ""}${suspected ? ", suspected" : ""}`;
        return `<td title="${esc(title)}"><span class="cell ${cls}">${esc(text)}</span>${suspected ? '<span class="suspected">S</span>' : ""}</td>`;
      });
      return `<tr class="${esc(m.condition)}"><th>${esc(m.name)}</th>${cells.join("")}</tr>`;
    });
    setHtml($("links"), head + rows.join(""));
  }

  // --- Reconfigurations ----------------------------------------------------------------
  function renderMeasures() {
    const ms = (value) => (value === undefined || value === null ? "-" : value.toFixed(1));
    const rows = Object.keys(state.measures)
      .sort((a, b) => Number(a) - Number(b))
      .map((key) => {
        const m = state.measures[key];
        return `<tr><td>${esc(`${m.kind} ${m.target}`)}</td><td>${esc(time(m.t_ns))}</td>` +
          `<td>${ms(m.detection_ms)}</td><td>${ms(m.decision_ms)}</td><td>${ms(m.switch_ms)}</td>` +
          `<td>${ms(m.restore_ms)}</td><td><b>${ms(m.total_ms)}</b></td>` +
          `<td>${esc(m.config ? `${m.config}, ${m.new_master || "-"}` : "-")}</td></tr>`;
      });
    setHtml($("measures").tBodies[0], rows.join("") ||
      '<tr><td colspan="8" class="muted">no fault, phase command or exclusion yet</td></tr>');
  }

  // --- The timeline --------------------------------------------------------------------
  // The timeline's geometry at cursor `at`: its window [start, end], and x and y of a time
  // and a lane (null: the faults lane).
  function timelineFrame(at) {
    const svg = $("timeline");
    const width = Math.max(400, svg.clientWidth || 900);
    const names = nodeNames(state.nodes);
    const frame = { svg, width, names, laneHeight: 18, left: 56, top: 16, at };
    frame.height = frame.top + (names.length + 1) * frame.laneHeight + 18;
    const windowS = Number($("window").value);
    frame.end = windowS ? at : lastT();
    frame.start = windowS ? Math.max(firstT(), at - windowS * NS) : firstT();
    frame.span = Math.max(1, frame.end - frame.start);
    frame.x = (t) => frame.left + ((t - frame.start) / frame.span) * (width - frame.left - 8);
    frame.y = (name) => frame.top + (name === null ? 0 : names.indexOf(name) + 1) * frame.laneHeight;
    return frame;
  }

  function renderTimeline(at) {
    const f = timelineFrame(at);
    const parts = [
      ...drawLanes(f), ...drawMeasures(f), ...drawMarkers(f), ...drawAxis(f),
    ];
    f.svg.setAttribute("height", f.height);
    f.svg.setAttribute("viewBox", `0 0 ${f.width} ${f.height}`);
    f.svg.dataset.start = f.start;
    f.svg.dataset.end = f.end;
    setHtml(f.svg, parts.join(""));
  }

  // A lane per node, coloured by its role (or down) over time, up to the cursor.
  function drawLanes(f) {
    const parts = [`<text class="lane-label" x="2" y="${f.y(null) + 12}">faults</text>`];
    for (const name of f.names) {
      const y = f.y(name);
      parts.push(`<text class="lane-label" x="2" y="${y + 12}">${esc(name)}</text>`);
      const lane = lanes[name] || [];
      lane.forEach(([t, key], k) => {
        const until = k + 1 < lane.length ? lane[k + 1][0] : f.at;
        if (until < f.start || t > f.end || !key) return;
        const x0 = f.x(Math.max(t, f.start));
        const x1 = f.x(Math.min(until, f.end));
        parts.push(`<rect class="seg ${esc(key)}" x="${x0.toFixed(1)}" y="${y + 2}" ` +
          `width="${Math.max(0.5, x1 - x0).toFixed(1)}" height="${f.laneHeight - 4}">` +
          `<title>${esc(`${name} ${key} from ${time(t)}`)}</title></rect>`);
      });
    }
    return parts;
  }

  // Each reconfiguration's detection, decision and switch, one after the other, on the
  // faults lane.
  function drawMeasures(f) {
    const parts = [];
    for (const m of Object.values(state.measures)) {
      let from = m.t_ns;
      for (const [name, figure] of [["detection", m.detection_ms], ["decision", m.decision_ms], ["switch", m.switch_ms]]) {
        if (figure === undefined || figure === null) continue;
        const to = from + figure * 1e6;
        if (to >= f.start && from <= f.end) {
          const x0 = f.x(Math.max(from, f.start));
          parts.push(`<rect class="span ${name}" x="${x0.toFixed(1)}" y="${f.y(null) + 12}" ` +
            `width="${Math.max(1, f.x(Math.min(to, f.end)) - x0).toFixed(1)}" height="4">` +
            `<title>${esc(`${m.kind} ${m.target}: ${name} ${figure.toFixed(1)} ms`)}</title></rect>`);
        }
        from = to;
      }
    }
    return parts;
  }

  // A marker per event with a sentence (checkpoints when asked), faded after the cursor:
  // at most MARKERS_MAX, those nearest the cursor (back from it, then on from it), so the
  // newest are drawn while following a run.
  function drawMarkers(f) {
    const showCheckpoints = $("show-checkpoints").checked;
    const first = lowerBound(f.start);
    const end = upperBound(f.end);
    const cut = Math.max(first, Math.min(end, upperBound(f.at)));
    const marker = (event) => {
      const onFaults = event.k === "fault" || event.n === null;
      const y = f.y(onFaults ? null : event.n) + f.laneHeight / 2;
      const cx = f.x(event.t).toFixed(1);
      const future = event.t > f.at ? ' opacity="0.3"' : "";
      const title = `<title>${esc(`${time(event.t)} ${event.d}`)}</title>`;
      return event.k === "checkpoint"
        ? `<rect class="m checkpoint" x="${cx}" y="${y - 4}" width="1" height="8"${future}>${title}</rect>`
        : `<circle class="m ${esc(event.k)}" cx="${cx}" cy="${y}" r="4"${future}>${title}</circle>`;
    };
    const shown = (event) => event.d && event.k !== "measure" && (event.k !== "checkpoint" || showCheckpoints);
    const earlier = [];
    const later = [];
    for (let k = cut - 1; k >= first && earlier.length < MARKERS_MAX; k -= 1) {
      if (shown(byTime[k])) earlier.push(marker(byTime[k]));
    }
    for (let k = cut; k < end && earlier.length + later.length < MARKERS_MAX; k += 1) {
      if (shown(byTime[k])) later.push(marker(byTime[k]));
    }
    const parts = earlier.reverse().concat(later);
    if (parts.length >= MARKERS_MAX) {
      parts.push(`<text class="axis" x="${f.width - 8}" y="${f.y(null) + 10}" text-anchor="end">` +
        `the ${MARKERS_MAX} markers nearest the cursor</text>`);
    }
    return parts;
  }

  // The axis, about eight ticks at round steps, and the cursor.
  function drawAxis(f) {
    const parts = [];
    const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 30, 60, 120, 300, 600, 1800, 3600];
    const step = steps.find((s) => f.span / NS / s <= 8) || 7200;
    const axisY = f.height - 4;
    for (let s = Math.ceil(seconds(f.start) / step) * step; s <= seconds(f.end) + 1e-9; s += step) {
      const tx = f.x(firstT() + s * NS).toFixed(1);
      parts.push(`<line x1="${tx}" x2="${tx}" y1="${f.top}" y2="${axisY - 10}" stroke="#eef1f3"/>`);
      parts.push(`<text class="axis" x="${tx}" y="${axisY}" text-anchor="middle">${+s.toFixed(1)} s</text>`);
    }
    if (f.at >= f.start && f.at <= f.end) {
      const cx = f.x(f.at).toFixed(1);
      parts.push(`<line class="cursor" x1="${cx}" x2="${cx}" y1="${f.top - 6}" y2="${axisY - 10}"/>`);
    }
    return parts;
  }

  // --- The event list ------------------------------------------------------------------
  // The list is rebuilt when the cursor goes back, the filter changes or events arrive out
  // of order; following a run, the new rows are put on top of it.
  let listed = null; // {end, show, first}: what the list shows
  let listOutOfOrder = false;

  function row(event) {
    return `<li class="${esc(event.k)}" data-i="${event.i}" data-t="${event.t}">` +
      `<span class="t">${esc(time(event.t))}</span><span class="n">${esc(event.n || "")}</span>${esc(event.d)}</li>`;
  }

  function renderEvents(at) {
    const show = $("show-checkpoints").checked;
    const listedEvent = (event) => event.d && (show || event.k !== "checkpoint");
    const end = upperBound(at);
    const list = $("events");
    const rows = [];
    const same = listed && listed.show === show && listed.first === firstT() && !listOutOfOrder;
    if (same && end === listed.end) return;
    if (same && end > listed.end) {
      for (let k = end - 1; k >= listed.end && rows.length < LIST_MAX; k -= 1) {
        if (listedEvent(byTime[k])) rows.push(row(byTime[k]));
      }
      if (rows.length) list.insertAdjacentHTML("afterbegin", rows.join(""));
      while (list.childElementCount > LIST_MAX) list.lastElementChild.remove();
    } else {
      for (let k = end - 1; k >= 0 && rows.length < LIST_MAX; k -= 1) {
        if (listedEvent(byTime[k])) rows.push(row(byTime[k]));
      }
      list.innerHTML = rows.join("");
    }
    listed = { end, show, first: firstT() };
    listOutOfOrder = false;
  }

  // --- The feed ------------------------------------------------------------------------
  function setConnection(kind, text) {
    const badge = $("connection");
    if (badge.className !== `badge ${kind}`) badge.className = `badge ${kind}`;
    setText(badge, text);
  }

  function handle(message) {
    if (message.status) {
      if (instance && message.status.instance !== instance) {
        location.reload(); // another console on this port: start again
        return;
      }
      instance = message.status.instance;
      status = message.status;
      setText($("run-dir"), status.run_dir);
    }
    if (message.mission) {
      mission = message.mission;
      $("mission-name").textContent = mission.name ? `\u2014 ${mission.name}` : "";
      document.title = `Keel console \u2014 ${mission.name || status.run_dir}`;
    }
    receive(message.events || []);
    setConnection("live", status && status.finished ? "finished run" : "connected");
    scheduleRender();
  }

  function connect() {
    const source = new EventSource("api/stream");
    source.onmessage = (message) => handle(JSON.parse(message.data));
    source.onerror = () => {
      setConnection("lost", "disconnected (the console stopped?): what arrived can still be played back");
    };
  }

  // --- Controls ------------------------------------------------------------------------
  $("play").addEventListener("click", () => {
    if (playing) {
      playing = false;
      remember();
      scheduleRender();
    } else {
      play();
    }
  });
  $("live").addEventListener("click", follow);
  $("seek").addEventListener("input", () => {
    seek(firstT() + (Number($("seek").value) / 1000) * (lastT() - firstT()), false);
  });
  $("speed").addEventListener("change", () => {
    speed = Number($("speed").value) || 1;
  });
  $("window").addEventListener("change", redrawTimeline);
  $("show-checkpoints").addEventListener("change", redrawTimeline);
  $("timeline").addEventListener("click", (click) => {
    const svg = $("timeline");
    const box = svg.getBoundingClientRect();
    const width = Math.max(400, svg.clientWidth || 900);
    const fraction = ((click.clientX - box.left) * (width / box.width) - 56) / (width - 56 - 8);
    const start = Number(svg.dataset.start);
    const end = Number(svg.dataset.end);
    if (fraction >= 0 && fraction <= 1) seek(start + fraction * (end - start), false);
  });
  $("events").addEventListener("click", (click) => {
    const row = click.target.closest("li");
    if (row) seek(Number(row.dataset.t), false);
  });
  document.addEventListener("keydown", (key) => {
    if (key.key === " " && key.target === document.body) {
      key.preventDefault();
      $("play").click();
    }
  });
  window.addEventListener("resize", redrawTimeline);
  window.addEventListener("hashchange", () => {
    readAddress();
    scheduleRender();
  });

  // The run's ground console (keel-cluster run --console): a line as on --ground's stdin,
  // sent with the key of the address the run printed (#k=; kept for this tab's reloads).
  // A replay, or a page opened without the key, has none.
  const given = new URLSearchParams(location.hash.slice(1)).get("k");
  if (given) sessionStorage.setItem("keel-command-key", given);
  const commandKey = sessionStorage.getItem("keel-command-key");
  let commandBusy = false;
  fetch("api/command").then((answer) => answer.json()).then((command) => {
    if (!command.enabled || !commandKey) return;
    commandOffered = true;
    $("command-line").placeholder = (command.examples || []).join(" | ");
    scheduleRender();
  }).catch(() => {});
  $("command").addEventListener("submit", (submit) => {
    submit.preventDefault();
    const line = $("command-line").value.trim();
    if (!line || !commandOffered || commandBusy) return;
    commandBusy = true;
    $("command-send").disabled = true;
    setText($("command-answer"), `sending ${line}`);
    fetch("api/command", {
      method: "POST",
      headers: {"Content-Type": "application/json", "X-Keel-Token": commandKey},
      body: JSON.stringify({line}),
    }).then((answer) => answer.text()).then((text) => {
      let result;
      try {
        result = JSON.parse(text);
      } catch (error) {
        result = {ok: false, error: text.trim()};
      }
      setText($("command-answer"), result.ok
        ? `applied: ${result.line}${result.note ? `; ${result.note}` : ""} (the timeline shows what the cluster did)`
        : `not applied: ${result.error}`);
      if (result.ok) $("command-line").value = "";
    }).catch((error) => setText($("command-answer"), `not applied: ${error}`)).finally(() => {
      commandBusy = false;
      $("command-send").disabled = false;
    });
  });

  readAddress();
  connect();
  scheduleRender();
})();
