// The page: a person plays the human side against the robots' policy (asmplan serve).
// It talks to the JSON API only; the robots' replies are the advisor's, posted as they come.
"use strict";

const state = { plan: null, planInfo: null, meshes: {}, session: null, advice: null,
                bars: [], lastParts: [], busy: false, open: {}, deviated: new Set() };

// Plotly with nothing that leaves the machine: no "Share chart" (plotly.js 4 uploads the
// chart, meshes included, to Plotly's cloud), no link to plotly's site, no server to send to.
const PLOT_CONFIG = {
  displaylogo: false, responsive: true, showLink: false, showSendToCloud: false,
  plotlyServerURL: "", modeBarButtonsToRemove: ["sendChartToCloud", "sendDataToCloud"],
};

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

async function start() {
  const params = new URLSearchParams(location.search);
  const plans = await api("GET", "/api/plans");
  if (!plans.length) throw new Error("this service has no plan");
  const wanted = params.get("plan");
  state.plan = (plans.find((p) => p.id === wanted) || plans[0]).id;
  state.planInfo = await api("GET", `/api/plans/${encodeURIComponent(state.plan)}`);
  document.getElementById("title").textContent =
    `${state.planInfo.assembly}: you are the person, the robots follow the robust plan`;
  const unit = state.planInfo.cost === "steps" ? "" : " s";
  const rows = state.planInfo.robustness || [];
  const w0 = isConcurrent() && rows.length ? rows[0].bound : state.planInfo.metrics.w0;
  document.getElementById("w0").textContent = fmt(w0) + unit;
  document.getElementById("wstar").textContent = fmt(state.planInfo.minimax) + unit;
  document.getElementById("concurrent-panel").hidden = !isConcurrent();
  document.getElementById("finishes-panel").hidden = !isConcurrent();
  state.meshes = await api("GET", `/api/plans/${encodeURIComponent(state.plan)}/meshes`);
  const session = await api("POST", "/api/sessions", { plan: state.plan });
  state.session = session.id;
  document.body.dataset.session = session.id;
  await show(session.advice);
}

function isConcurrent() {
  return state.planInfo && state.planInfo.turn_model === "concurrent";
}

// One step of the game: show the advice; on the robots' turn, play their reply.
async function show(advice) {
  if (isConcurrent()) return showConcurrent(advice);
  state.advice = advice;
  document.getElementById("elapsed").textContent = fmt(advice.elapsed);
  document.getElementById("guarantee").textContent = fmt(advice.total_bound);
  drawView(advice);
  drawGantt();
  const options = document.getElementById("options");
  options.replaceChildren();
  if (advice.finished) return finish(advice);
  if (advice.turn === "robot") {
    setStatus("the robots are working ...");
    const move = advice.robots[0];
    const item = el("li", { "data-op": move.operation, "data-agent": move.agent },
      `${move.operation} by ${move.agent}: ${move.description}`);
    document.getElementById("robot-log").append(item);
    await record(move, "robot");
    return;
  }
  setStatus("your turn: choose what you do next (green: what the plan asks)");
  document.body.dataset.ready = "1";
  for (const opt of advice.options) {
    const asked = advice.instruction && advice.instruction.operation === opt.operation &&
      advice.instruction.agent === opt.agent;
    const button = el("button", { "data-op": opt.operation, "data-agent": opt.agent,
                                  "data-worst": opt.worst, class: asked ? "asked" : "" });
    button.append(el("span", {}, `${opt.operation} ${opt.description} (${fmt(opt.cost)})`));
    button.append(el("span", { class: "worst" }, `worst case ${fmt(opt.worst)}`));
    const alike = alikePick(opt);
    button.addEventListener("click", () =>
      record({ ...opt, operation: alike ? alike.value : opt.operation }, "human"));
    options.append(button);
    if (alike) options.append(alike);
  }
}

// An option naming one of several alike parts (any of them is as good): a choice of which.
function alikePick(opt) {
  if (!opt.alike || opt.alike.length < 2) return null;
  const pick = el("select", { class: "alike", "data-alike-for": opt.operation,
                              title: "alike parts: any of them is as good" });
  for (const op of opt.alike) {
    const info = (state.planInfo.operations || {})[op];
    const parts = info && info.parts ? info.parts.join(", ") : op;
    pick.append(el("option", { value: op }, `${op} (${parts})`));
  }
  pick.value = opt.operation;
  pick.addEventListener("click", (ev) => ev.stopPropagation());
  return pick;
}

function alikeNote(item) {
  return item.alike && item.alike.length > 1 ? ` (or alike: ${item.alike.slice(1).join(", ")})` : "";
}

async function record(move, who) {
  const before = state.advice;
  await post({ kind: "finished", operation: move.operation, agent: move.agent }, (advice) =>
    state.bars.push({ agent: move.agent, operation: move.operation, who,
                      start: before.elapsed, end: advice.elapsed }));
}

// ---------------------------------------------------------------- the concurrent game
// At each event the robots commit first (their reply is logged), then the person starts
// operations; a completion ("next completion" buttons) advances the clock.

function sideOf(agent) {
  if (agent.includes(":")) return agent.split(":").pop();
  return (state.planInfo.agents || {})[agent] || "human";
}

function trackBars(advice) {
  state.open = state.open || {};
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
  state.deviated = state.deviated || new Set();
  const fresh = state.advice === null || state.advice.state !== advice.state ||
    state.advice.elapsed !== advice.elapsed;
  state.advice = advice;
  trackBars(advice);
  document.getElementById("elapsed").textContent = fmt(advice.elapsed);
  document.getElementById("clock").textContent = fmt(advice.elapsed);
  document.getElementById("guarantee").textContent = fmt(advice.total_bound);
  drawView(advice);
  drawGantt();
  if (fresh && !advice.finished) {  // a new event: the robots' commitment
    const log = document.getElementById("robot-log");
    if (!advice.robots.length) {
      log.append(el("li", { "data-time": advice.elapsed, class: "wait" },
        `t = ${fmt(advice.elapsed)}: the robots wait`));
    }
    for (const r of advice.robots) {
      log.append(el("li", { "data-op": r.operation, "data-agent": r.agent, "data-time": advice.elapsed },
        `t = ${fmt(advice.elapsed)}: ${r.agent} starts ${r.operation} (${r.description})`));
    }
  }
  const running = document.getElementById("running");
  running.replaceChildren(...advice.running.map((r) =>
    el("li", { "data-op": r.operation, "data-agent": r.agent },
      `${r.agent}: ${r.operation} ${describe(r.operation)} (${fmt(r.remaining)} left)`)));
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
    const button = el("button", { "data-kind": "start", "data-op": opt.operation,
                                  "data-agent": opt.agent, "data-worst": opt.worst,
                                  "data-deviation": opt.deviation ? "1" : "0",
                                  "data-duration": opt.cost,
                                  class: asked ? "asked" : opt.deviation ? "deviation" : "" });
    button.append(el("span", {}, `${opt.agent} starts ${opt.operation} ${opt.description}`));
    let pick = null;
    if (opt.durations.length > 1) {
      pick = el("select", { "data-op": opt.operation, title: "how long you will take" });
      for (const d of opt.durations) pick.append(el("option", { value: d }, `${fmt(d)} s`));
      pick.value = String(opt.cost);
      pick.addEventListener("click", (ev) => ev.stopPropagation());
    } else {
      button.append(el("span", {}, ` (${fmt(opt.cost)} s)`));
    }
    button.append(el("span", { class: "worst" }, `worst case ${fmt(opt.worst)}`));
    const alike = alikePick(opt);
    button.addEventListener("click", () => {
      const op = alike ? alike.value : opt.operation;
      if (opt.deviation) state.deviated.add(op);
      post({ kind: "started", operation: op, agent: opt.agent,
             duration: pick ? Number(pick.value) : opt.cost });
    });
    options.append(button);
    if (pick) options.append(pick);
    if (alike) options.append(alike);
  }
  for (const f of advice.finishes) {
    const button = el("button", { "data-kind": "finish", "data-op": f.operation,
                                  "data-agent": f.agent, "data-time": f.time,
                                  "data-worst": f.worst });
    button.append(el("span", {}, `${f.agent} finishes ${f.operation} at t = ${fmt(f.time)}`));
    button.append(el("span", { class: "worst" }, `worst case ${fmt(f.worst)}`));
    button.addEventListener("click", () =>
      post({ kind: "finished", operation: f.operation, agent: f.agent, time: f.time }));
    finishes.append(button);
  }
  setStatus(advice.finishes.length
    ? "start an operation, or let the cell run to its next completion"
    : "start an operation (you do not idle while you have something to do)");
  document.body.dataset.ready = "1";
}

function describe(op) {
  const info = (state.planInfo.operations || {})[op];
  return info ? info.description : "";
}

// Post an event; on success call `then(advice)` (if given) and show the new advice.
async function post(event, then) {
  if (state.busy) return;
  state.busy = true;
  document.body.dataset.ready = "0";
  try {
    const advice = await api("POST", `/api/sessions/${state.session}/events`, event);
    if (then) then(advice);
    document.getElementById("error").textContent = "";
    state.busy = false;
    await show(advice);
  } catch (err) {
    state.busy = false;
    document.body.dataset.ready = "1";
    document.getElementById("error").textContent = err.message;
  }
}

function setStatus(text) {
  document.getElementById("status").textContent = text;
}

function drawView(advice) {
  const ids = Object.keys(state.meshes);
  const note = document.getElementById("view-note");
  if (!ids.length) {
    note.textContent = "no part meshes in this plan: the 3D view is empty";
    return;
  }
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
    (fresh.size ? ` (just now: ${[...fresh].join(", ")})` : "");
}

function drawGantt() {
  // Running operations are drawn to their planned end, faded.
  const left = Object.fromEntries((state.advice.running || []).map((r) => [r.operation, r.remaining]));
  const open = Object.values(state.open || {}).map((b) =>
    ({ ...b, end: state.advice.elapsed + (left[b.operation] || 0), running: true }));
  const bars = [...state.bars, ...open].filter((b) => b.end > b.start);
  const colour = { robot: "#2e9d4a", human: "#9e9e9e" };
  const trace = {
    type: "bar", orientation: "h", y: bars.map((b) => b.agent),
    x: bars.map((b) => b.end - b.start), base: bars.map((b) => b.start),
    text: bars.map((b) => b.operation), textposition: "inside",
    marker: { color: bars.map((b) => colour[b.who]), opacity: bars.map((b) => b.running ? 0.45 : 1),
              line: { color: bars.map((b) => b.deviation ? "#d62728" : "#ffffff"),
                      width: bars.map((b) => b.deviation ? 3 : 0) } },
    hoverinfo: "text+x",
  };
  const layout = { margin: { l: 50, r: 10, t: 30, b: 30 }, title: { text: "Gantt chart", font: { size: 13 } },
                   xaxis: { title: { text: "time" }, rangemode: "tozero" },
                   yaxis: { type: "category" } };
  plot("gantt", [trace], layout);
}

async function finish(advice) {
  setStatus("the assembly is complete");
  const session = await api("GET", `/api/sessions/${state.session}`);
  const out = session.outcome;
  document.getElementById("final-cost").textContent = fmt(out.cost);
  document.getElementById("final-w0").textContent = fmt(out.w0);
  document.getElementById("final-wstar").textContent = fmt(out.minimax);
  document.getElementById("final-deviations").textContent = String(out.deviations);
  if (out.robustness) {  // the concurrent game: W*(0) and W*(k) for the deviations made
    const rows = out.robustness.filter((r) => r.k !== null);
    const row = rows.find((r) => r.k === out.deviations) || rows[rows.length - 1];
    document.getElementById("final-w0").textContent = fmt(rows[0].bound);
    document.getElementById("final-wk").textContent = `${fmt(row.bound)} (k = ${row.k})`;
    document.getElementById("final-wk-note").hidden = false;
  }
  document.getElementById("final").hidden = false;
  document.body.dataset.ready = "done";
  const items = await api("GET", "/api/questionnaire");
  const form = document.getElementById("questionnaire");
  form.replaceChildren();
  if (!items.length) return;
  for (const item of items) {
    form.append(el("label", { for: `q-${item.id}` }, item.text));
    const input = item.scale
      ? el("input", { type: "range", id: `q-${item.id}`, name: item.id,
                      min: item.scale[0], max: item.scale[1], value: item.scale[0] })
      : el("input", { type: "text", id: `q-${item.id}`, name: item.id, maxlength: "500" });
    form.append(input);
  }
  const submit = el("button", { type: "submit", id: "submit-answers" }, "send the answers");
  form.append(submit);
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const answers = {};
    for (const item of items) {
      const v = form.elements[item.id].value;
      answers[item.id] = item.scale ? Number(v) : v;
    }
    try {
      await api("POST", `/api/sessions/${state.session}/answers`, { answers });
      form.hidden = true;
      document.getElementById("thanks").hidden = false;
    } catch (err) {
      document.getElementById("error").textContent = err.message;
    }
  });
}

start().catch((err) => {
  document.getElementById("error").textContent = err.message;
  setStatus("could not start");
});
