// The page of `jax3dc serve`: uploads photos one request each (in the order given), polls the jobs,
// shows a finished one in the viewer with its verdict and an edit form per joint. Every text that
// comes from a file name or the server is set with textContent, never parsed as HTML.
"use strict";

const POLL_MS = 1000;
const AXES = ["+x", "-x", "+y", "-y", "+z", "-z"];
const TYPES = ["hinge", "slide", "fixed"];
const KEEP = "";  // the line select's value that keeps the pivot where it is

const state = { jobs: [], selected: null, version: 0, polling: null, uploads: true, loaded: false };
const $ = (id) => document.getElementById(id);

function el(tag, props = {}, children = []) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(props)) {
    if (key === "text") node.textContent = value;
    else if (key === "class") node.className = value;
    else if (key.startsWith("data-")) node.setAttribute(key, value);
    else node[key] = value;
  }
  for (const child of children) node.append(child);
  return node;
}

async function api(url, options = {}) {
  const reply = await fetch(url, options);
  let data = null;
  try { data = await reply.json(); } catch (e) { /* not JSON: reported below */ }
  if (!reply.ok) throw new Error((data && data.error) || `${reply.status} ${reply.statusText}`);
  return data;
}

function say(id, text, isError = false) {
  const node = $(id);
  node.textContent = text;
  node.classList.toggle("error", isError);
}

function verdictText(verdict) {
  if (!verdict) return "no physics verdict";
  return verdict.ok ? "physics check: passes" : "physics check: fails";
}

// ---- uploads and the job list

async function upload(files) {
  for (const file of files) {  // one at a time: the queue keeps the order they were given in
    const form = new FormData();
    form.append("image", file, file.name);
    say("message", `uploading ${file.name}…`);
    try {
      await api("/api/jobs", { method: "POST", body: form });
      say("message", `${file.name}: queued`);
    } catch (e) {
      say("message", e.message, true);
    }
    await refresh();
  }
}

function jobItem(job) {
  let status = job.state;
  if (job.state === "queued" && job.position) status += ` (${job.position} before it)`;
  if (job.state === "done") status += ` — ${verdictText(job.verdict)}`;
  if (job.state === "failed") status += `: ${job.error}`;
  const cls = job.state === "done" ? `state done ${job.verdict && job.verdict.ok ? "passes" : "fails"}` : `state ${job.state}`;
  const item = el("li", { "data-job": job.id, "data-state": job.state }, [
    el("div", { class: "name", text: job.name }),
    el("div", { class: cls, text: status }),
  ]);
  if (job.id === state.selected) item.classList.add("selected");
  item.addEventListener("click", () => select(job.id));
  return item;
}

async function refresh() {
  const data = await api("/api/jobs");
  const before = new Map(state.jobs.map((j) => [j.id, j.state]));
  state.jobs = data.jobs;
  $("jobs").replaceChildren(...state.jobs.map(jobItem));
  // a job that finished since the last look (or was submitted and done in between) opens, once the page has loaded
  const finished = state.loaded && state.jobs.find((j) => j.state === "done" && before.get(j.id) !== "done");
  if (!state.selected && finished) {
    say("message", "");  // "queued" is over: the list says where each photo stands
    select(finished.id);
  }
  else if (!state.selected && !state.uploads && state.jobs.length) select(state.jobs[0].id);
  const busy = state.jobs.some((j) => j.state === "queued" || j.state === "running");
  if (busy && !state.polling) state.polling = setInterval(() => refresh().catch(() => {}), POLL_MS);
  if (!busy && state.polling) { clearInterval(state.polling); state.polling = null; }
}

// ---- one object: verdict, viewer, edit forms

async function select(id) {
  state.selected = id;
  for (const item of $("jobs").children) item.classList.toggle("selected", item.dataset.job === id);
  const job = await api(`/api/jobs/${encodeURIComponent(id)}`);
  $("object").hidden = false;
  $("object-name").textContent = job.name;
  say("edit-message", "");
  if (job.state !== "done") {
    say("verdict", job.state === "failed" ? `failed: ${job.error}` : job.state, job.state === "failed");
    $("viewer").removeAttribute("src");
    $("zip").hidden = true;
    $("joints").replaceChildren();
    return;
  }
  await showObject(job);
}

async function showObject(job) {
  const verdict = $("verdict");
  verdict.textContent = verdictText(job.verdict);
  verdict.className = job.verdict && job.verdict.ok ? "passes" : "fails";
  verdict.dataset.ok = job.verdict ? String(job.verdict.ok) : "";
  $("zip").hidden = false;
  $("zip").href = job.zip;
  state.version += 1;
  if (job.viewer) $("viewer").src = `${job.viewer}?v=${state.version}`;  // the page itself changes with an edit
  const data = await api(`/api/jobs/${encodeURIComponent(job.id)}/joints`);
  $("joints").replaceChildren(...data.joints.filter((r) => r.type !== "root").map((r) => jointForm(job, r, data.verdict)));
}

function options(select, values, selected) {
  select.replaceChildren(...values.map(([value, label]) => el("option", { value, text: label, selected: value === selected })));
}

function numberInput(value, step) {
  return el("input", { type: "number", step, value: value === null || value === undefined ? "" : String(value) });
}

function jointForm(job, row, verdict) {
  const named = typeof row.axis === "string" || row.axis === null;
  const free = named ? [0, 0, 1] : row.axis;
  const joint = verdict && verdict.joints[String(row.part)];
  const form = el("form", { "data-part": String(row.part) });
  const type = el("select", { name: "type" });
  options(type, TYPES.map((t) => [t, t]), row.type);
  const axis = el("select", { name: "axis" });
  options(axis, [...AXES.map((a) => [a, a]), ["free", "free [x, y, z]"]], named ? (row.axis || "+z") : "free");
  const vector = free.map((c) => numberInput(Math.round(c * 1000) / 1000, "0.001"));
  const line = el("select", { name: "line" });
  const lo = numberInput(row.range ? row.range[0] : null, "0.001");
  const hi = numberInput(row.range ? row.range[1] : null, "0.001");
  const vectorRow = el("label", {}, ["axis vector", el("span", { class: "pair" }, vector)]);

  function fillLines() {
    const letter = axis.value === "free" ? null : axis.value[1];
    const names = letter ? row.lines[letter] : [];
    const keep = row.line && row.type !== "fixed" ? `${row.line} (now)` : "keep the pivot";
    options(line, [[KEEP, keep], ...names.filter((n) => n !== row.line || letter !== (row.axis || "")[1]).map((n) => [n, n])], KEEP);
    vectorRow.hidden = axis.value !== "free";
    const moving = type.value !== "fixed";
    for (const input of [axis, line, lo, hi, ...vector]) input.disabled = !moving;
  }
  type.addEventListener("change", fillLines);
  axis.addEventListener("change", fillLines);

  const title = `part ${row.part}` + (row.name ? ` (${row.name})` : "") + ` on part ${row.parent}`;
  const children = [el("legend", { text: title })];
  if (joint) {
    children.push(el("div", { class: joint.ok ? "passes" : "fails", text: joint.ok ? "joint passes" : "joint flagged" }));
    for (const reason of joint.reasons) children.push(el("div", { class: "reasons", text: reason }));
  }
  children.push(
    el("label", {}, ["type", type]),
    el("label", {}, ["axis", axis]),
    vectorRow,
    el("label", {}, ["hinge line", line]),
    el("label", {}, ["range", el("span", { class: "pair" }, [lo, hi])]),
    el("button", { type: "submit", class: "button", text: "Apply" }),
  );
  form.append(el("fieldset", {}, children));
  if (joint && !joint.ok) form.classList.add("flagged");
  fillLines();

  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const ops = [];
    const typeChanged = type.value !== row.type;
    if (typeChanged) ops.push({ op: "set_type", value: type.value });
    if (type.value !== "fixed") {
      const value = axis.value === "free" ? vector.map((v) => Number(v.value)) : axis.value;
      const axisChanged = JSON.stringify(value) !== JSON.stringify(row.axis);
      if (axisChanged || row.type === "fixed") ops.push({ op: "set_axis", value });
      if (line.value !== KEEP) ops.push({ op: "set_line", value: line.value });
      const range = [Number(lo.value), Number(hi.value)];
      if (row.range && lo.value !== "" && hi.value !== "" && JSON.stringify(range) !== JSON.stringify(row.range)) {
        ops.push({ op: "set_range", value: range });
      }
    }
    if (!ops.length) { say("edit-message", `part ${row.part}: nothing changed`); return; }
    say("edit-message", `part ${row.part}: checking…`);
    try {
      const reply = await api(`/api/jobs/${encodeURIComponent(job.id)}/edit`, {
        method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify({ part: row.part, ops }),
      });
      await showObject(reply.job);
      say("edit-message", `part ${row.part}: edited; ${verdictText(reply.job.verdict)}`);
      refresh();
    } catch (e) {
      say("edit-message", e.message, true);
    }
  });
  return form;
}

// ---- start

function dropArea() {
  const drop = $("drop");
  drop.hidden = false;
  for (const name of ["dragenter", "dragover"]) {
    drop.addEventListener(name, (e) => { e.preventDefault(); drop.classList.add("over"); });
  }
  for (const name of ["dragleave", "drop"]) {
    drop.addEventListener(name, () => drop.classList.remove("over"));
  }
  drop.addEventListener("drop", (e) => { e.preventDefault(); upload([...e.dataTransfer.files]); });
  $("files").addEventListener("change", (e) => { upload([...e.target.files]); e.target.value = ""; });
  $("folder").addEventListener("change", (e) => {  // a folder's image files, by name as the batch command orders them
    const images = [...e.target.files].filter((f) => f.type.startsWith("image/"));
    images.sort((a, b) => (a.webkitRelativePath < b.webkitRelativePath ? -1 : 1));
    if (!images.length) say("message", "no image files in that folder", true);
    upload(images);
    e.target.value = "";
  });
}

async function start() {
  const settings = await api("/api/settings");
  state.uploads = settings.uploads;
  if (settings.uploads) dropArea();
  await refresh();
  state.loaded = true;
  document.body.dataset.ready = "true";
}

start().catch((e) => say("message", e.message, true));
