// The page: a person plays the human side against the robots' policy (asmplan serve).
// It talks to the JSON API only; the robots' replies are the advisor's, posted as they come.
"use strict";

const state = { plan: null, planInfo: null, meshes: {}, session: null, advice: null,
                bars: [], lastParts: [], busy: false };

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
  document.getElementById("w0").textContent = fmt(state.planInfo.metrics.w0) + unit;
  document.getElementById("wstar").textContent = fmt(state.planInfo.minimax) + unit;
  state.meshes = await api("GET", `/api/plans/${encodeURIComponent(state.plan)}/meshes`);
  const session = await api("POST", "/api/sessions", { plan: state.plan });
  state.session = session.id;
  document.body.dataset.session = session.id;
  await show(session.advice);
}

// One step of the game: show the advice; on the robots' turn, play their reply.
async function show(advice) {
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
    button.addEventListener("click", () => record(opt, "human"));
    options.append(button);
  }
}

async function record(move, who) {
  if (state.busy) return;
  state.busy = true;
  document.body.dataset.ready = "0";
  const before = state.advice;
  try {
    const advice = await api("POST", `/api/sessions/${state.session}/events`,
      { kind: "finished", operation: move.operation, agent: move.agent });
    state.bars.push({ agent: move.agent, operation: move.operation, who,
                      start: before.elapsed, end: advice.elapsed });
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
  Plotly.react("view", traces, layout, { displaylogo: false, responsive: true });
  note.textContent = `placed: ${[...present].join(", ") || "nothing yet"}` +
    (fresh.size ? ` (just now: ${[...fresh].join(", ")})` : "");
}

function drawGantt() {
  const bars = state.bars.filter((b) => b.end > b.start);
  const colour = { robot: "#2e9d4a", human: "#9e9e9e" };
  const trace = {
    type: "bar", orientation: "h", y: bars.map((b) => b.agent),
    x: bars.map((b) => b.end - b.start), base: bars.map((b) => b.start),
    text: bars.map((b) => b.operation), textposition: "inside",
    marker: { color: bars.map((b) => colour[b.who]) }, hoverinfo: "text+x",
  };
  const layout = { margin: { l: 50, r: 10, t: 30, b: 30 }, title: { text: "Gantt chart", font: { size: 13 } },
                   xaxis: { title: { text: "time" }, rangemode: "tozero" },
                   yaxis: { type: "category" } };
  Plotly.react("gantt", [trace], layout, { displaylogo: false, responsive: true });
}

async function finish(advice) {
  setStatus("the assembly is complete");
  const session = await api("GET", `/api/sessions/${state.session}`);
  const out = session.outcome;
  document.getElementById("final-cost").textContent = fmt(out.cost);
  document.getElementById("final-w0").textContent = fmt(out.w0);
  document.getElementById("final-wstar").textContent = fmt(out.minimax);
  document.getElementById("final-deviations").textContent = String(out.deviations);
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
