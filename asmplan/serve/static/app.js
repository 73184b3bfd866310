// The page: a person plays the human side against the robots' policy (asmplan serve).
// It talks to the JSON API only; the robots' replies are the advisor's, posted as they come.
// Each option says what the robots do in reply and the worst case it leads to; the line
// behind that worst case opens on request. After each move the focus goes to the next one.
"use strict";

const state = { plan: null, condition: null, planInfo: null, meshes: {}, session: null,
                advice: null, bars: [], lastParts: [], busy: false, open: {},
                deviated: new Set(), study: null, participant: null, block: null,
                speed: null, clock: null, clockAt: 0, seen: -1, poll: null, logged: new Set() };
const POLL_MS = 300;  // real time: how often the page asks the service for its clock

// Plotly with nothing that leaves the machine: no "Share chart" (plotly.js 4 uploads the
// chart, meshes included, to Plotly's cloud), no link to plotly's site, no server to send to.
const PLOT_CONFIG = {
  displaylogo: false, responsive: true, showLink: false, showSendToCloud: false,
  plotlyServerURL: "", modeBarButtonsToRemove: ["sendChartToCloud", "sendDataToCloud"],
};
const SIDE_COLOUR = { robot: "#2e9d4a", human: "#6b7f99" };
const AHEAD_COLOUR = { robot: "#cfe8d5", human: "#dde3ec" };
const DEVIATION_COLOUR = "#b3261e";

// Draw a plotly figure; its toolbar stays out of the Tab order (the moves come first).
async function plot(id, traces, layout) {
  const gd = await Plotly.react(id, traces, layout, PLOT_CONFIG);
  untab(gd);
  if (!gd.dataset.untab) {
    gd.dataset.untab = "1";
    gd.on("plotly_afterplot", () => untab(gd));
  }
}

function untab(gd) {
  for (const node of gd.querySelectorAll(".modebar-btn, .modebar a")) node.tabIndex = -1;
}

function fmt(x) {
  return Number.isInteger(x) ? String(x) : Number(x).toFixed(2).replace(/\.?0+$/, "");
}

// A cost with its unit: seconds, or steps when the plan counts operations.
function qty(x) {
  if (state.planInfo && state.planInfo.cost === "steps") {
    return `${fmt(x)} ${Number(x) === 1 ? "step" : "steps"}`;
  }
  return `${fmt(x)} s`;
}

function span(a, b) {
  return state.planInfo && state.planInfo.cost === "steps"
    ? `steps ${fmt(a)}-${fmt(b)}` : `${fmt(a)}-${fmt(b)} s`;
}

async function api(method, path, body) {
  const opts = { method, headers: {} };
  if (body !== undefined) {
    opts.headers["content-type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  const res = await fetch(path, opts);
  const data = await res.json().catch(() => ({}));
  if (!res.ok) {
    const detail = typeof data.detail === "string" ? data.detail : JSON.stringify(data.detail);
    throw new Error(`${res.status}: ${detail}`);
  }
  return data;
}

function el(tag, attrs, text) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (text !== undefined) node.textContent = text;
  return node;
}

function setError(text) {
  document.getElementById("error").textContent = text;
}

// The plans of this service in the picker; the one asked for in ?plan=, or the first.
// An unknown ?plan= is an error naming the plans there are (no session is made).
async function pickPlan() {
  const params = new URLSearchParams(location.search);
  const plans = await api("GET", "/api/plans");
  if (!plans.length) throw new Error("this service has no plan");
  const pick = document.getElementById("plan-pick");
  pick.replaceChildren(...plans.map((p) =>
    el("option", { value: p.id }, `${p.assembly} (${p.turn_model}, ${p.id})`)));
  const wanted = params.get("plan");
  const found = wanted === null ? plans[0] : plans.find((p) => p.id === wanted);
  document.getElementById("plan-form").hidden = plans.length < 2 && found !== undefined;
  if (found === undefined) {
    document.getElementById("plan-form").hidden = false;
    document.body.dataset.ready = "error";
    throw new Error(`unknown plan "${wanted}": this service runs ` +
      `${plans.map((p) => p.id).join(", ")}; pick one above`);
  }
  pick.value = found.id;
  return found.id;
}

// Without a study: the plan picked (or the session in ?session= resumed). With a study
// (asmplan serve --study): the consent, the participant's code, then each round in turn.
async function start() {
  const params = new URLSearchParams(location.search);
  state.study = await api("GET", "/api/study").catch(() => null);
  if (state.study) return startStudy(params);
  if (params.get("session")) return resume(params.get("session"));
  await openPlan(await pickPlan(), null);
  await show(await startAdvice());
}

// Load a plan (of a study's robot condition): its numbers, meshes, and an empty record.
async function openPlan(plan, condition, title) {
  state.plan = plan;
  state.condition = condition;
  const query = condition ? `?condition=${encodeURIComponent(condition)}` : "";
  state.planInfo = await api("GET", `/api/plans/${encodeURIComponent(plan)}${query}`);
  document.getElementById("title").textContent = title ||
    `${state.planInfo.assembly}: you are the person, the robots follow the robust plan`;
  const steps = state.planInfo.cost === "steps";
  document.querySelector("#numbers div dt").textContent = steps ? "cost so far" : "time so far";
  const rows = state.planInfo.robustness || [];
  const w0 = isConcurrent() && rows.length ? rows[0].bound : state.planInfo.metrics.w0;
  document.getElementById("w0").textContent = qty(w0);
  document.getElementById("wstar").textContent = qty(state.planInfo.minimax);
  document.getElementById("concurrent-panel").hidden = !isConcurrent();
  document.getElementById("finishes-panel").hidden = !isConcurrent();
  state.meshes = await api("GET", `/api/plans/${encodeURIComponent(plan)}/meshes`);
  stopPoll();
  Object.assign(state, { session: null, advice: null, bars: [], lastParts: [], open: {},
                         deviated: new Set(), speed: state.planInfo.realtime || null,
                         clock: null, seen: -1, logged: new Set() });
  document.getElementById("realtime").hidden = !state.speed;
  document.getElementById("finishes-title").textContent = state.speed
    ? "If you start nothing: what the cell does next (the clock finishes operations)"
    : "Next completion (what happens next in the cell)";
  delete document.body.dataset.session;
  document.getElementById("robot-log").replaceChildren();
  document.getElementById("last-move").textContent = "";
  for (const id of ["final", "thanks", "next-round"]) document.getElementById(id).hidden = true;
  document.getElementById("questionnaire").hidden = false;
  document.getElementById("play-panel").hidden = false;
}

// The advice at the plan's start, explained; no session is made until the first move.
function startAdvice() {
  const query = state.condition ? `?condition=${encodeURIComponent(state.condition)}` : "";
  return api("GET", `/api/plans/${encodeURIComponent(state.plan)}/explain${query}`);
}

// Resume a session (a reload): its plan and condition, the Gantt chart from its events.
async function resume(sid, title) {
  const view = await api("GET", `/api/sessions/${encodeURIComponent(sid)}`);
  await openPlan(view.plan, view.condition || null, title);
  useSession(view.id);
  rebuild(view);
  document.getElementById("last-move").textContent =
    `Resumed: ${view.events.length} event(s) so far.`;
  if (view.advice.finished) return show(view.advice);
  if (state.speed) startPoll();
  return show(await explained(view.advice));
}

// The Gantt chart's bars and the robots' log from a session's events (a reload, or the
// real-time clock, whose completions come between the page's looks): a completion with no
// start seen ends a bar that began its duration earlier (the robots' starts are not events
// in the concurrent game).
function rebuild(view) {
  const bars = [], open = {};
  let last = 0;
  for (const e of view.events) {
    const who = e.by === "robot" ? "robot" : "human";
    if (e.kind === "started") {
      open[e.operation] = { agent: e.agent, operation: e.operation, start: e.elapsed, who,
                            deviation: !!e.deviation };
      if (e.deviation) state.deviated.add(e.operation);
    } else if (open[e.operation]) {
      bars.push({ ...open[e.operation], end: e.elapsed });
      delete open[e.operation];
    } else {
      const d = duration(e.operation, e.agent);
      const start = d === null ? last : Math.max(0, e.elapsed - d);
      bars.push({ agent: e.agent, operation: e.operation, start, end: e.elapsed, who,
                  deviation: !!e.deviation });
    }
    last = e.elapsed;
  }
  for (const r of view.advice.running || []) {  // started by the robots' commitment
    if (open[r.operation]) continue;
    const d = duration(r.operation, r.agent);
    open[r.operation] = { agent: r.agent, operation: r.operation, who: sideOf(r.agent),
                          start: d === null ? view.advice.elapsed
                            : view.advice.elapsed - (d - r.remaining),
                          deviation: state.deviated.has(r.operation) };
  }
  state.bars = bars;
  state.open = open;
  state.seen = view.events.length;
  const robots = [...bars, ...Object.values(open)].filter((b) => b.who === "robot")
    .sort((a, b) => a.start - b.start);
  for (const b of robots) {
    const key = `${b.operation}|${b.agent}`;
    if (state.logged.has(key)) continue;
    state.logged.add(key);
    logRobot({ "data-op": b.operation, "data-agent": b.agent, "data-time": b.start },
      `t = ${qty(b.start)}: ${b.agent} starts ${b.operation} (${describe(b.operation)})`);
  }
}

// An agent's duration for an operation in the plan (null: not known).
function duration(op, agent) {
  const info = (state.planInfo.operations || {})[op];
  const d = info && info.agents ? info.agents[agent.split(":")[0]] : undefined;
  return typeof d === "number" ? d : null;
}

function useSession(sid) {
  state.session = sid;
  document.body.dataset.session = sid;
  const params = new URLSearchParams(location.search);
  params.set("session", sid);
  if (state.study) params.delete("session");
  history.replaceState(null, "", `?${params}`);
}

// ---------------------------------------------------------------- a study
async function startStudy(params) {
  const panel = document.getElementById("study-panel");
  panel.hidden = false;
  document.getElementById("play-panel").hidden = true;
  document.getElementById("title").textContent = state.study.title;
  document.getElementById("consent").textContent = state.study.consent || "";
  const code = document.getElementById("participant");
  code.value = params.get("participant") || "";
  document.body.dataset.ready = "consent";
  document.getElementById("agree").focus();
  document.getElementById("study-form").onsubmit = async (ev) => {
    ev.preventDefault();
    try {
      const body = code.value.trim() ? { participant: code.value.trim() } : {};
      const record = await api("POST", "/api/participants", body);
      state.participant = record.id;
      history.replaceState(null, "", `?participant=${encodeURIComponent(record.id)}`);
      panel.hidden = true;
      setError("");
      await nextRound(record);
    } catch (err) {
      setError(err.message);
    }
  };
}

// The participant's next round (block): resumed if its session is open, else new.
async function nextRound(record) {
  const n = record.blocks.length;
  if (record.next === null) {
    document.getElementById("play-panel").hidden = false;
    document.getElementById("final").hidden = false;
    document.getElementById("questionnaire").hidden = true;
    document.getElementById("thanks").hidden = false;
    document.getElementById("thanks").textContent =
      `Thank you, ${record.id}: the study is complete (${n} round${n > 1 ? "s" : ""}).`;
    document.getElementById("thanks").focus();
    document.body.dataset.ready = "study-done";
    return;
  }
  const b = record.blocks[record.next];
  state.block = b.block;
  const title = `${state.study.title}: round ${b.block + 1} of ${n}, ${b.label}`;
  document.body.dataset.round = String(b.block);
  if (b.session) return resume(b.session, title);
  await openPlan(b.plan, b.condition, title);
  await show(await startAdvice());
}

// The advice with its explanation (each option's reply and worst line, the plan ahead),
// asked for beside the event's plain advice; the robots' own turns need none.
async function explained(advice) {
  if (advice.finished || (!isConcurrent() && advice.turn === "robot")) return advice;
  return api("GET", `/api/sessions/${state.session}/explain`);
}

// An event: the session's next, or the first move, which makes the session (real time,
// robots first: no event, the clock makes their moves).
async function send(event) {
  if (state.session) return api("POST", `/api/sessions/${state.session}/events`, event);
  const body = state.study ? { participant: state.participant, block: state.block }
    : { plan: state.plan };
  if (event) body.event = event;
  const view = await api("POST", "/api/sessions", body);
  useSession(view.id);
  if (state.speed) startPoll();
  return view.advice;
}

function isConcurrent() {
  return state.planInfo && state.planInfo.turn_model === "concurrent";
}

function showNumbers(advice) {
  document.getElementById("elapsed").textContent = qty(advice.elapsed);
  document.getElementById("guarantee").textContent = qty(advice.total_bound);
}

// One step of the game: show the advice; on the robots' turn, play their reply.
async function show(advice) {
  if (isConcurrent()) return showConcurrent(advice);
  state.advice = advice;
  showNumbers(advice);
  drawView(advice);
  drawGantt();
  const options = document.getElementById("options");
  options.replaceChildren();
  if (advice.finished) return finish(advice);
  if (state.speed) showClock();
  if (advice.turn === "robot" && state.speed) {  // the clock starts and finishes them
    setStatus("the robots are working: the clock runs");
    if (!state.session) await send(null);
    return ready();
  }
  if (advice.turn === "robot") {
    setStatus("the robots are working ...");
    const move = advice.robots[0];
    logRobot({ "data-op": move.operation, "data-agent": move.agent },
      `at ${qty(advice.elapsed)}: ${move.agent} does ${move.operation} (${move.description})`);
    await record(move, "robot");
    return;
  }
  if (state.speed && advice.running.length) {
    const r = advice.running[0];
    setStatus(`you (${r.agent}) are doing ${r.operation}: the clock runs until it is done`);
    return ready();
  }
  setStatus(state.speed ? "your turn: choose what you do next; the clock waits for you"
    : "your turn: choose what you do next (marked: what the plan asks)");
  for (const opt of advice.options) {
    const asked = advice.instruction !== null && advice.instruction.operation === opt.operation &&
      advice.instruction.agent === opt.agent;
    options.append(optionBlock(opt, asked, (op) => {
      noteMove(opt, op, asked);
      if (state.speed) return post({ kind: "started", operation: op, agent: opt.agent });
      return record({ ...opt, operation: op }, "human");
    }));
  }
  ready();
}

// One option: its pickers (which alike part, how long), the move's button (what it is,
// whether the plan asks it, the robots' reply and the worst case), and the line behind it.
function optionBlock(opt, asked, act) {
  const block = el("div", { class: "option" });
  const pickers = el("div", { class: "pickers" });
  const alike = alikePick(opt);
  if (alike) pickers.append(labelled("part", alike));
  let duration = null;
  if (opt.durations && opt.durations.length > 1) {
    duration = el("select", { "data-op": opt.operation, class: "duration",
                              "aria-label": `how long you take for ${opt.operation}` });
    for (const d of opt.durations) duration.append(el("option", { value: d }, qty(d)));
    duration.value = String(opt.cost);
    pickers.append(labelled("you take", duration));
  }
  if (pickers.childElementCount) block.append(pickers);
  const deviation = !asked && opt.deviation === true;
  const button = el("button", {
    type: "button", class: `move${asked ? " asked" : deviation ? " deviation" : ""}`,
    "data-kind": isConcurrent() ? "start" : "move", "data-op": opt.operation,
    "data-agent": opt.agent, "data-worst": opt.worst, "data-deviation": deviation ? "1" : "0",
    "data-duration": opt.cost,
  });
  const what = el("span", { class: "what" });
  if (asked) what.append(el("span", { class: "tag asked" }, "the plan asks this"));
  if (deviation) what.append(el("span", { class: "tag deviation" }, "deviation"));
  const verb = isConcurrent() ? `${opt.agent} starts` : "do";
  const took = duration ? "" : ` (${qty(opt.cost)})`;
  what.append(document.createTextNode(`${verb} ${opt.operation} ${opt.description}${took}`));
  what.append(el("span", { class: "worst" }, `worst case ${qty(opt.worst)}`));
  button.append(what);
  if (opt.why) button.append(el("span", { class: "why" }, opt.why));
  button.addEventListener("click", () => {
    const op = alike ? alike.value : opt.operation;
    act(op, duration ? Number(duration.value) : opt.cost);
  });
  block.append(button);
  if (opt.line && opt.line.length) block.append(lineDetails(opt));
  return block;
}

function labelled(text, control) {
  const label = el("label", {}, `${text} `);
  label.append(control);
  return label;
}

// The line behind an option's worst case, step by step (opened on request).
function lineDetails(opt, after) {
  const details = el("details", { class: "line", "data-op": opt.operation });
  details.append(el("summary", {},
    `why ${qty(opt.worst)}? the worst line after ${after || opt.operation}`));
  const list = el("ol");
  for (const s of opt.line) {
    const who = s.side === "robot" ? s.agent : `${s.agent} (person)`;
    const text = `${span(s.start, s.end)}: ${who} ${s.operation} ${s.description}` +
      (s.deviation ? " (a deviation)" : "");
    list.append(el("li", { class: s.deviation ? "deviation" : "" }, text));
  }
  list.append(el("li", {}, `the assembly is complete at ${qty(opt.worst)}`));
  details.append(list);
  return details;
}

// An option naming one of several alike parts (any of them is as good): a choice of which.
function alikePick(opt) {
  if (!opt.alike || opt.alike.length < 2) return null;
  const pick = el("select", { class: "alike", "data-alike-for": opt.operation,
                              "aria-label": `which alike part for ${opt.operation}`,
                              title: "alike parts: any of them is as good" });
  for (const op of opt.alike) {
    const info = (state.planInfo.operations || {})[op];
    const parts = info && info.parts ? info.parts.join(", ") : op;
    pick.append(el("option", { value: op }, `${op} (${parts})`));
  }
  pick.value = opt.operation;
  return pick;
}

function alikeNote(item) {
  return item.alike && item.alike.length > 1 ? ` (or alike: ${item.alike.slice(1).join(", ")})` : "";
}

// Say what the person just did, in words: following the plan or a deviation from it.
function noteMove(opt, op, asked) {
  const note = document.getElementById("last-move");
  const told = state.advice.instruction;
  const deviation = !asked && opt.deviation === true;
  note.className = deviation ? "deviation" : "";
  note.textContent = deviation
    ? `You did ${op}: a deviation (the plan asked ${told ? told.operation : "otherwise"}).`
    : `You did ${op}, as the plan asks.`;
  logPerson(op, opt.agent, deviation);
}

function logRobot(attrs, text) {
  logItem(el("li", attrs, text));
}

function logItem(item) {
  const log = document.getElementById("robot-log");
  log.append(item);
  log.scrollTop = log.scrollHeight;
}

function logPerson(op, agent, deviation) {
  const at = qty(state.advice.elapsed);
  logItem(el("li", {
    class: deviation ? "person deviation" : "person", "data-person": op,
  }, `at ${at}: you (${agent}) ${op}${deviation ? ", a deviation" : ""}`));
}

async function record(move, who) {
  const before = state.advice;
  await post({ kind: "finished", operation: move.operation, agent: move.agent }, (advice) =>
    state.bars.push({ agent: move.agent, operation: move.operation, who,
                      start: before.elapsed, end: advice.elapsed,
                      deviation: who === "human" && move.deviation === true }));
}

// ---------------------------------------------------------------- the concurrent game
// At each event the robots commit first (their reply is logged), then the person starts
// operations; a completion ("next completion" buttons) advances the clock.

function sideOf(agent) {
  if (agent.includes(":")) return agent.split(":").pop();
  return (state.planInfo.agents || {})[agent] || "human";
}

function trackBars(advice) {
  const running = new Set(advice.running.map((r) => r.operation));
  for (const r of advice.running) {
    if (!state.open[r.operation]) {
      state.open[r.operation] = { agent: r.agent, operation: r.operation, start: advice.elapsed,
                                  who: sideOf(r.agent), deviation: state.deviated.has(r.operation) };
    }
  }
  for (const [op, bar] of Object.entries(state.open)) {
    if (!running.has(op) && advice.done.includes(op)) {
      state.bars.push({ ...bar, end: advice.elapsed });
      delete state.open[op];
    }
  }
}

async function showConcurrent(advice) {
  const fresh = state.advice === null || state.advice.state !== advice.state ||
    state.advice.elapsed !== advice.elapsed;
  state.advice = advice;
  if (!state.speed) trackBars(advice);
  showNumbers(advice);
  document.getElementById("clock").textContent = qty(advice.elapsed);
  drawView(advice);
  drawGantt();
  if (state.speed) {
    showClock();
  } else if (fresh && !advice.finished) {  // a new event: the robots' commitment
    if (!advice.robots.length) {
      logRobot({ "data-time": advice.elapsed, class: "wait" },
        `t = ${qty(advice.elapsed)}: the robots wait`);
    }
    for (const r of advice.robots) {
      logRobot({ "data-op": r.operation, "data-agent": r.agent, "data-time": advice.elapsed },
        `t = ${qty(advice.elapsed)}: ${r.agent} starts ${r.operation} (${r.description})`);
    }
  }
  showRunning(advice.elapsed);
  const told = advice.instructions.map((i) => i.operation === null
    ? `${i.agent}: wait` : `${i.agent}: ${i.operation} ${i.description}${alikeNote(i)}`);
  document.getElementById("instruction").textContent = told.length
    ? `· the plan asks ${told.join("; ")}` : "";
  const options = document.getElementById("options");
  const finishes = document.getElementById("finishes");
  options.replaceChildren();
  finishes.replaceChildren();
  if (advice.finished) {
    document.getElementById("finishes-panel").hidden = true;
    return finish(advice);
  }
  for (const opt of advice.options) {
    const asked = advice.instructions.some((i) => i.operation === opt.operation &&
      i.agent === opt.agent);
    options.append(optionBlock(opt, asked, (op, duration) => {
      if (opt.deviation) state.deviated.add(op);
      noteMove(opt, op, asked);
      return post({ kind: "started", operation: op, agent: opt.agent, duration });
    }));
  }
  for (const f of advice.finishes) finishes.append(finishBlock(f));
  if (state.speed) {
    setStatus(advice.finishes.length
      ? "the cell runs: start an operation when you choose, or let it run"
      : "the clock waits for you: start an operation");
  } else {
    setStatus(advice.finishes.length
      ? "start an operation, or let the cell run to its next completion"
      : "start an operation (you do not idle while you have something to do)");
  }
  ready();
}

// A completion the person may let the cell run to: what it is and the worst case after
// it, the robots' reply then (why), and the line behind the worst case on request. In real
// time the clock makes it (no button: it says what happens if she starts nothing).
function finishBlock(f) {
  const block = el("div", { class: "option finish" });
  const attrs = { "data-kind": "finish", "data-op": f.operation, "data-agent": f.agent,
                  "data-time": f.time, "data-worst": f.worst };
  const who = f.side === "human" ? `you (${f.agent}) finish` : `${f.agent} finishes`;
  const what = el("span", { class: "what" }, `${who} ${f.operation} at ${qty(f.time)}`);
  what.append(el("span", { class: "worst" }, `worst case ${qty(f.worst)}`));
  let node;
  if (state.speed) {
    node = el("div", { ...attrs, class: "upcoming" });
  } else {
    node = el("button", { ...attrs, type: "button", class: "move" });
    node.addEventListener("click", () =>
      post({ kind: "finished", operation: f.operation, agent: f.agent, time: f.time }));
  }
  node.append(what);
  if (f.why) node.append(el("span", { class: "why" }, f.why));
  block.append(node);
  if (f.line && f.line.length) {
    block.append(lineDetails(f, `${f.agent} finishes ${f.operation} at ${qty(f.time)}`));
  }
  return block;
}

// ---------------------------------------------------------------- real time
// The service's clock finishes operations (asmplan serve --realtime): the page looks at
// /api/sessions/{id}/advice every POLL_MS and, when events came, reads the session again.

function startPoll() {
  if (state.poll || !state.session) return;
  let busy = false;
  state.poll = setInterval(async () => {
    if (busy || state.busy) return;
    busy = true;
    try {
      const look = await api("GET", `/api/sessions/${state.session}/advice`);
      state.clock = look.clock;
      state.clockAt = performance.now();
      if (look.events !== state.seen || look.finished) await refresh();
      else showClock();
    } catch (err) {
      setError(err.message);
    } finally {
      busy = false;
    }
  }, POLL_MS);
}

function stopPoll() {
  if (state.poll) clearInterval(state.poll);
  state.poll = null;
}

// The session read again (its events: the bars and the log), then shown explained.
async function refresh() {
  const view = await api("GET", `/api/sessions/${state.session}`);
  state.clock = view.clock;
  state.clockAt = performance.now();
  rebuild(view);
  if (view.advice.finished) {
    stopPoll();
    return show(view.advice);
  }
  return show(await explained(view.advice));
}

// The game time now: the clock's, running on between looks unless it waits for the person.
function gameNow() {
  const c = state.clock;
  if (!c) return state.advice ? state.advice.elapsed : 0;
  if (c.holding || !state.session) return c.game_time;
  const t = c.game_time + (performance.now() - state.clockAt) / 1000 * c.speed;
  return c.next ? Math.min(t, c.next.time) : t;
}

function showClock() {
  const node = document.getElementById("realtime");
  const c = state.clock;
  const now = gameNow();
  node.dataset.time = String(now);
  node.dataset.holding = c && c.holding ? "1" : "0";
  let text = `clock ${qty(Math.round(now * 10) / 10)}, running at ${fmt(state.speed)} s of ` +
    "cell time per second";
  if (!state.session || (c && c.holding)) text += "; it waits for you to start something";
  else if (c && c.next) {
    const verb = c.next.kind === "started" ? "starts" : "finishes";
    const wait = Math.max(0, (c.next.time - now) / state.speed);
    text += `; next: ${c.next.agent} ${verb} ${c.next.operation} at ${qty(c.next.time)}` +
      ` (in ${wait.toFixed(1)} s)`;
  }
  node.textContent = text;
  if (isConcurrent() && state.advice) {
    document.getElementById("clock").textContent = qty(Math.round(now * 10) / 10);
    showRunning(now);
  }
  const gd = document.getElementById("gantt");
  if (gd.layout && gd.layout.shapes && gd.layout.shapes.length) {
    Plotly.relayout(gd, { "shapes[0].x0": now, "shapes[0].x1": now, "annotations[0].x": now,
                          "annotations[0].text": `now ${qty(Math.round(now * 10) / 10)}` });
  }
}

// What runs, each with the time it has left at game time `now`.
function showRunning(now) {
  const advice = state.advice;
  const running = document.getElementById("running");
  running.replaceChildren(...advice.running.map((r) => {
    const left = Math.max(0, Math.round((r.remaining - (now - advice.elapsed)) * 10) / 10);
    return el("li", { "data-op": r.operation, "data-agent": r.agent },
      `${r.agent}: ${r.operation} ${describe(r.operation)} (${qty(left)} left)`);
  }));
}

function describe(op) {
  const info = (state.planInfo.operations || {})[op];
  return info ? info.description : "";
}

// The advice is shown: mark the page ready and put the focus on the next move (the plan's
// instruction if it is an option, else the cell's next completion (the plan says wait), else
// the first option); an
// option's pickers (which part, how long) are one Shift+Tab before its button.
function ready() {
  document.body.dataset.ready = "1";
  const target = document.querySelector("#options button.move.asked") ||
    document.querySelector("#finishes button.move") ||
    document.querySelector("#options button.move");
  if (target) target.focus();
}

// Post an event; on success call `then(advice)` (if given) and show the new advice.
async function post(event, then) {
  if (state.busy) return;
  state.busy = true;
  document.body.dataset.ready = "0";
  try {
    const plain = await send(event);
    if (state.speed) {  // the record is the session's events (the clock's among them)
      setError("");
      await refresh();
      state.busy = false;
      return;
    }
    if (then) then(plain);
    const advice = await explained(plain);
    setError("");
    state.busy = false;
    await show(advice);
  } catch (err) {
    state.busy = false;
    document.body.dataset.ready = "1";
    setError(err.message);
  }
}

function setStatus(text) {
  document.getElementById("status").textContent = text;
}

function drawView(advice) {
  const ids = Object.keys(state.meshes);
  const note = document.getElementById("view-note");
  document.getElementById("view-panel").hidden = !ids.length;  // no meshes: no empty box
  if (!ids.length) return;
  const present = new Set([...state.planInfo.base_parts, ...advice.parts]);
  const fresh = new Set(advice.parts.filter((p) => !state.lastParts.includes(p)));
  state.lastParts = advice.parts.slice();
  const traces = ids.map((id) => {
    const m = state.meshes[id];
    const placed = present.has(id);
    return {
      type: "mesh3d", name: id, x: m.x, y: m.y, z: m.z, i: m.i, j: m.j, k: m.k,
      color: fresh.has(id) ? "#f28c28" : placed ? "#4f81bd" : "#bbbbbb",
      opacity: placed ? 1.0 : 0.12, flatshading: true, hovertext: `${id} ${m.name}`,
      hoverinfo: "text", showlegend: false,
    };
  });
  const layout = { margin: { l: 0, r: 0, t: 0, b: 0 }, uirevision: "keep",
                   scene: { aspectmode: "data", xaxis: { visible: false },
                            yaxis: { visible: false }, zaxis: { visible: false } } };
  plot("view", traces, layout);
  note.textContent = `placed: ${[...present].join(", ") || "nothing yet"}` +
    (fresh.size ? ` (just now: ${[...fresh].join(", ")}, orange)` : "");
}

// The Gantt chart: what was done, what runs, and the plan ahead if the person follows it,
// with a "now" line and a legend.
function drawGantt() {
  const now = state.speed ? Math.max(state.advice.elapsed, gameNow()) : state.advice.elapsed;
  const left = Object.fromEntries((state.advice.running || []).map((r) => [r.operation, r.remaining]));
  const running = Object.values(state.open).map((b) =>
    ({ ...b, end: state.advice.elapsed + (left[b.operation] || 0) }));
  const ahead = (state.advice.ahead || []).filter((s) => !state.open[s.operation]).map((s) =>
    ({ agent: s.agent, operation: s.operation, start: s.start, end: s.end, who: s.side,
       deviation: s.deviation, description: s.description }));
  // [legend, bars, fill (per side when an object), text colour, pattern]
  const groups = [
    ["robots, done", state.bars.filter((b) => b.who === "robot"), SIDE_COLOUR, "white", ""],
    ["you, done", state.bars.filter((b) => b.who !== "robot" && !b.deviation), SIDE_COLOUR,
     "white", ""],
    ["you, a deviation", state.bars.filter((b) => b.who !== "robot" && b.deviation), "#f6d5d2",
     "#222", "/"],
    ["running (to its planned end)", running, { robot: "#8cc79b", human: "#a9b6c8" }, "#222", ""],
    ["the plan ahead (if you follow it)", ahead, AHEAD_COLOUR, "#333", ""],
  ];
  const agents = Object.keys(state.planInfo.agents || {}).sort((a, b) =>
    (sideOf(a) === "human" ? 0 : 1) - (sideOf(b) === "human" ? 0 : 1) || a.localeCompare(b));
  const end = Math.max(state.advice.total_bound || 0, now,
    ...ahead.map((b) => b.end), ...running.map((b) => b.end), 1);
  const roomy = (b) => b.end - b.start >= end / (document.getElementById("gantt").clientWidth / 28);
  const traces = groups.map(([name, bars, fill, ink, pattern]) => {
    const kept = bars.filter((b) => b.end > b.start);
    const colour = typeof fill === "string" ? fill
      : kept.map((b) => fill[b.who === "robot" ? "robot" : "human"]);
    return {
      type: "bar", orientation: "h", name, y: kept.map((b) => b.agent),
      x: kept.map((b) => b.end - b.start), base: kept.map((b) => b.start),
      text: kept.map((b) => roomy(b) ? b.operation : ""), textposition: "inside",
      insidetextanchor: "middle", textangle: 0, textfont: { size: 12, color: ink },
      constraintext: "none",
      hovertext: kept.map((b) => `${b.agent} ${b.operation} ${describe(b.operation)}: ` +
        span(b.start, b.end)),
      hoverinfo: "text",
      marker: { color: colour, line: { color: "#555", width: 0.6 },
                pattern: { shape: pattern, fgcolor: DEVIATION_COLOUR, solidity: 0.25 } },
      showlegend: true,
    };
  });
  const unit = state.planInfo.cost === "steps" ? "steps" : "time (s)";
  const layout = {
    margin: { l: 48, r: 10, t: 30, b: 40 }, barmode: "overlay",
    title: { text: "Gantt chart", font: { size: 13 }, x: 0.01, xanchor: "left" },
    xaxis: { title: { text: unit }, range: [0, end * 1.02] },
    yaxis: { type: "category", categoryorder: "array", categoryarray: agents.slice().reverse() },
    legend: { orientation: "h", y: -0.28, font: { size: 11 } },
    shapes: [{ type: "line", x0: now, x1: now, yref: "paper", y0: 0, y1: 1,
               line: { color: DEVIATION_COLOUR, width: 2, dash: "dot" } }],
    annotations: [{ x: now, y: 1, yref: "paper", yanchor: "bottom", text: `now ${qty(now)}`,
                    xanchor: now > 0.8 * end ? "right" : "left",
                    showarrow: false, font: { size: 11, color: DEVIATION_COLOUR } }],
  };
  plot("gantt", traces, layout);
  const last = Math.max(now, ...ahead.map((b) => b.end), ...running.map((b) => b.end));
  document.getElementById("gantt-note").textContent =
    `now: ${qty(now)}; if you follow the plan from here the assembly is done at ${qty(last)}; ` +
    `the worst that can still happen: ${qty(state.advice.total_bound)}.`;
}

// A number shown with its unit, kept bare in data-value (for tests and scripts).
function setNumber(id, x) {
  const node = document.getElementById(id);
  node.textContent = qty(x);
  node.dataset.value = String(x);
}

async function finish(advice) {
  stopPoll();
  setStatus("the assembly is complete");
  if (state.speed) {
    const node = document.getElementById("realtime");
    node.textContent = `the clock stopped at ${qty(advice.elapsed)}: the assembly is complete`;
    node.dataset.time = String(advice.elapsed);
    node.dataset.holding = "0";
  }
  const session = await api("GET", `/api/sessions/${state.session}`);
  const out = session.outcome;
  setNumber("final-cost", out.cost);
  setNumber("final-w0", out.w0);
  setNumber("final-wstar", out.minimax);
  document.getElementById("final-deviations").textContent = String(out.deviations);
  if (out.robustness) {  // the concurrent game: W*(0) and W*(k) for the deviations made
    const rows = out.robustness.filter((r) => r.k !== null);
    const row = rows.find((r) => r.k === out.deviations) || rows[rows.length - 1];
    setNumber("final-w0", rows[0].bound);
    document.getElementById("final-wk").textContent = `${qty(row.bound)} (k = ${row.k})`;
    document.getElementById("final-wk-note").hidden = false;
  }
  document.getElementById("final").hidden = false;
  document.getElementById("final-title").focus();
  const items = await api("GET", "/api/questionnaire");
  questionnaire(items);
  document.body.dataset.ready = "done";
}

// The questionnaire: a scale item is a row of radio buttons with none chosen (an item left
// alone is missing, never a default value); a text item a text field.
function questionnaire(items) {
  const form = document.getElementById("questionnaire");
  form.replaceChildren();
  if (!items.length) return;
  for (const item of items) {
    if (item.scale) {
      const set = el("fieldset", { "data-item": item.id });
      set.append(el("legend", {}, item.text + (item.required ? " (required)" : "")));
      const row = el("div", { class: "scale" });
      const [lo, hi] = item.scale;
      const words = item.labels || {};
      for (let v = lo; v <= hi; v++) {
        const id = `q-${item.id}-${v}`;
        const label = el("label", { for: id });
        label.append(el("input", { type: "radio", id, name: item.id, value: v }));
        label.append(document.createTextNode(` ${v}${words[v] ? ` (${words[v]})` : ""}`));
        row.append(label);
      }
      set.append(row);
      form.append(set);
    } else {
      form.append(el("label", { for: `q-${item.id}`, class: "text" }, item.text));
      form.append(el("input", { type: "text", id: `q-${item.id}`, name: item.id, maxlength: "500" }));
    }
  }
  form.append(el("button", { type: "submit", id: "submit-answers" }, "send the answers"));
  form.onsubmit = async (ev) => {
    ev.preventDefault();
    const answers = {};
    for (const item of items) {
      if (item.scale) {
        const chosen = form.querySelector(`input[name="${CSS.escape(item.id)}"]:checked`);
        if (chosen) answers[item.id] = Number(chosen.value);
      } else {
        const v = form.elements[item.id].value.trim();
        if (v) answers[item.id] = v;
      }
    }
    try {
      await api("POST", `/api/sessions/${state.session}/answers`, { answers });
      form.hidden = true;
      document.getElementById("thanks").hidden = false;
      setError("");
      if (state.study) return offerNextRound();
      document.getElementById("thanks").focus();
    } catch (err) {
      setError(err.message);
    }
  };
}

// After a study round's answers: a button to the next round (or the end of the study).
async function offerNextRound() {
  const record = await api("GET", `/api/participants/${encodeURIComponent(state.participant)}`);
  const button = document.getElementById("next-round");
  button.textContent = record.next === null ? "finish the study" : "go on to the next round";
  button.hidden = false;
  button.onclick = () => nextRound(record);
  button.focus();
  document.body.dataset.ready = "answered";
}

start().catch((err) => {
  setError(err.message);
  setStatus("could not start");
  if (document.body.dataset.ready === "error") document.getElementById("plan-pick").focus();
});
