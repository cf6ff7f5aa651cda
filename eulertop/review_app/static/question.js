"use strict";
// One written question across all students: read an answer, tick the rubric, submit.

const desk = document.getElementById("desk");
const question = desk.dataset.question;
const $ = (id) => document.getElementById(id);
const state = {
  meta: null, answers: [], index: -1, current: null, comments: {},
  dirty: false, warned: false, busy: false, asked: 0, loading: false, queued: [],
};

function shortcutsOn() {
  return $("shortcuts").checked;
}

function checkedItems() {
  return [...$("items").querySelectorAll("input")].filter((b) => b.checked)
    .map((b) => Number(b.dataset.index));
}

function renderRubric() {
  const kept = new Set(checkedItems());
  const items = $("items");
  const editors = $("points-items");
  items.replaceChildren();
  editors.replaceChildren();
  state.meta.rubric.forEach((item, i) => {
    items.append(rubricItem(item, i, kept.has(i)));
    editors.append(pointsEditor(item, i));
  });
}

function rubricItem(item, i, checked) {
  const row = document.createElement("p");
  const box = document.createElement("input");
  box.type = "checkbox";
  box.id = `item-${i}`;
  box.dataset.index = i;
  box.checked = checked;
  box.addEventListener("change", changed);
  const label = document.createElement("label");
  label.htmlFor = box.id;
  const key = document.createElement("kbd");
  key.textContent = String(i + 1);
  const text = document.createElement("span");
  text.innerHTML = item.html;  // the instructor's rubric, rendered and escaped by the desk
  label.append(key, " ", text,
    ` (${points(item.points)} point${item.points === 1 ? "" : "s"})`);
  row.append(box, " ", label);
  return row;
}

function pointsEditor(item, i) {
  const row = document.createElement("p");
  const label = document.createElement("label");
  label.htmlFor = `points-${i}`;
  label.textContent = `Item ${i + 1}, points`;
  const input = document.createElement("input");
  input.type = "number";
  input.step = "0.25";
  input.min = "0";
  input.id = `points-${i}`;
  input.value = item.points;
  const apply = document.createElement("button");
  apply.type = "button";
  apply.textContent = `Set item ${i + 1}'s points`;
  apply.addEventListener("click", () => setPoints(i, Number(input.value)));
  row.append(label, " ", input, " ", apply);
  return row;
}

function renderProgress(all) {
  const p = all[question] || {};
  $("progress").max = Math.max(p.written || 0, 1);
  $("progress").value = p.reviewed || 0;
  const stale = p.stale ? `, ${p.stale} of them stale` : "";
  $("progress-text").textContent = `${p.reviewed || 0} of ${p.written || 0} written answers ` +
    `reviewed; ${p.pending || 0} pending${stale}.`;
}

function renderComments() {
  const select = $("saved");
  select.replaceChildren();
  for (const name of Object.keys(state.comments).sort()) {
    select.append(new Option(name, name));
  }
  $("insert").disabled = select.options.length === 0;
}

function updateScore() {
  if (!state.meta) {
    return;
  }
  const given = checkedItems().reduce((sum, i) => sum + state.meta.rubric[i].points, 0);
  const adjust = Number($("adjust").value) || 0;
  const max = state.meta.points;
  const score = Math.min(Math.max(given + adjust, 0), max);
  $("score").textContent = `Score with this review: ${points(score)} of ${points(max)} points.`;
}

function changed() {
  state.dirty = true;
  state.warned = false;
  updateScore();
}

function describe(found) {
  const n = state.answers.length;
  $("position").textContent = `Answer ${state.index + 1} of ${n}: ${found.status}, ` +
    `${points(found.points)} of ${points(found.max)} points`;
  $("who").textContent = found.student === undefined
    ? `Anonymous (answer ${found.id}).`
    : `${found.student}${found.name ? ` (${found.name})` : ""}, answer ${found.id}.`;
  const review = found.review;
  $("reviewed-by").textContent = review
    ? `Reviewed by ${review.by} at ${review.at}` +
      (review.stale ? "; stale: the student's text changed since." : ".")
    : "Not reviewed yet.";
}

function render(found) {
  state.current = found;
  describe(found);
  $("text").innerHTML = found.html;  // written_html: sanitised by the desk, under its CSP
  const given = new Set(found.review ? found.review.rubric : []);
  for (const box of $("items").querySelectorAll("input")) {
    box.checked = given.has(Number(box.dataset.index));
  }
  $("adjust").value = found.review ? found.review.adjust : 0;
  $("comment").value = found.review ? found.review.comment : "";
  const reviewable = ["pending", "reviewed"].includes(found.status);
  $("rubric").disabled = !reviewable;
  $("submit").disabled = !reviewable;
  state.dirty = false;
  state.warned = false;
  updateScore();
  history.replaceState(null, "", `#${found.id}`);
  desk.dataset.shown = found.id;
}

async function show(index, force = false) {
  const n = state.answers.length;
  if (n === 0) {
    say("No student was asked this question.");
    return;
  }
  if (state.dirty && !force && !state.warned) {
    state.warned = true;
    say("This review is not submitted: press s to submit it, or the same key again to " +
        "leave it.", true);
    return;
  }
  const wanted = ((index % n) + n) % n;
  const asked = ++state.asked;  // a later move wins over an earlier one still loading
  const names = $("names").checked ? "&names=1" : "";
  state.loading = true;
  try {
    const found = await api(`/api/answer?id=${state.answers[wanted].id}${names}`);
    if (asked !== state.asked) {
      return;
    }
    state.index = wanted;
    state.answers[wanted] = {...state.answers[wanted], status: found.status,
      review: found.review};
    render(found);
    state.loading = false;
    state.queued.splice(0).forEach((i) => toggle(i));  // pressed while it loaded: for it
  } finally {
    if (asked === state.asked) {
      state.loading = false;
    }
  }
}

async function nextPending(from) {
  // Asked of the desk each time: another TA may have reviewed some since this page loaded.
  const waiting = new Set(await api(`/api/pending?question=${encodeURIComponent(question)}`));
  const n = state.answers.length;
  for (let step = 1; step <= n; step++) {
    const i = (from + step) % n;
    if (waiting.has(state.answers[i].id)) {
      return i;
    }
  }
  return null;
}

async function submit() {
  if (state.busy) {
    say("Still saving the review before: press s again once it is saved.", true);
    return;
  }
  if (!state.current || $("submit").disabled) {
    return;
  }
  state.busy = true;
  const body = {id: state.current.id, rubric: checkedItems(),
    adjust: Number($("adjust").value) || 0, comment: $("comment").value};
  try {
    const found = await api("/api/review", body);
    const at = state.index;
    state.answers[at] = {...state.answers[at], status: found.status, review: found.review};
    renderProgress(found.progress);
    state.dirty = false;
    desk.dataset.saved = found.id;
    say(`Saved answer ${at + 1}: ${points(found.points)} of ${points(found.max)} points.`);
    const next = await nextPending(at);
    await show(next === null ? at : next, true);
    if (next === null) {
      say(`Saved answer ${at + 1}. Every written answer of this question has a review.`);
    }
    $("position").focus();  // out of the comment: the keys work again on the next answer
  } catch (error) {
    say(`Not saved: ${error.message}`, true);
  } finally {
    state.busy = false;
  }
}

async function setPoints(i, value) {
  try {
    state.meta = await api("/api/rubric", {question, item: i, points: value});
    renderRubric();
    renderProgress({[question]: state.meta.progress});
    say(`Item ${i + 1} is now worth ${points(value)} points; every student who has it ` +
        "was rescored.");
    await show(state.index, true);
  } catch (error) {
    say(`Not changed: ${error.message}`, true);
  }
}

function toggle(i) {
  if (state.loading) {
    state.queued.push(i);
    return;
  }
  const box = $(`item-${i}`);
  if (box && !box.disabled && !$("rubric").disabled) {
    box.checked = !box.checked;
    changed();
  }
}

function insertComment() {
  const text = state.comments[$("saved").value];
  if (text !== undefined) {
    const comment = $("comment");
    comment.value = comment.value ? `${comment.value}\n\n${text}` : text;
    changed();
    comment.focus();
  }
}

async function keepComment() {
  const name = $("save-name").value.trim();
  try {
    state.comments = await api("/api/comments", {question, name, text: $("comment").value});
    renderComments();
    $("saved").value = name;
    say(`Kept the comment as "${name}".`);
  } catch (error) {
    say(`Not kept: ${error.message}`, true);
  }
}

const KEYS = {
  j: () => show(state.index + 1),
  k: () => show(state.index - 1),
  n: async () => {
    const next = await nextPending(state.index);
    return next === null ? say("No answer of this question waits for a review.")
      : show(next);
  },
  s: submit,
  a: () => $("adjust").focus(),
  c: () => $("comment").focus(),
  "?": () => { $("help").open = !$("help").open; },
};

function onKey(event) {
  if (event.key === "Enter" && (event.ctrlKey || event.metaKey)) {
    event.preventDefault();
    submit();
    return;
  }
  if (typing(event.target)) {
    if (event.key === "Escape") {
      event.target.blur();
    }
    return;
  }
  if (event.ctrlKey || event.metaKey || event.altKey || !shortcutsOn()) {
    return;
  }
  if (/^[1-9]$/.test(event.key)) {
    toggle(Number(event.key) - 1);
  } else if (KEYS[event.key]) {
    KEYS[event.key]();
  } else {
    return;
  }
  event.preventDefault();
}

function wire() {
  document.addEventListener("keydown", onKey);
  $("review").addEventListener("submit", (event) => { event.preventDefault(); submit(); });
  $("adjust").addEventListener("input", changed);
  $("comment").addEventListener("input", changed);
  $("previous").addEventListener("click", () => show(state.index - 1));
  $("next").addEventListener("click", () => show(state.index + 1));
  $("next-pending").addEventListener("click", KEYS.n);
  $("names").addEventListener("change", () => show(state.index, true));
  $("insert").addEventListener("click", insertComment);
  $("save-comment").addEventListener("click", keepComment);
  $("shortcuts").checked = localStorage.getItem("eulertop-review-shortcuts") !== "off";
  $("shortcuts").addEventListener("change", () => localStorage.setItem(
    "eulertop-review-shortcuts", $("shortcuts").checked ? "on" : "off"));
}

async function start() {
  wire();
  const q = encodeURIComponent(question);
  const [questions, answers, comments] = await Promise.all([
    api("/api/questions"), api(`/api/written?question=${q}`), api(`/api/comments?question=${q}`),
  ]);
  state.meta = questions.find((one) => one.question === question);
  state.answers = answers;
  state.comments = comments;
  $("number").textContent = state.meta.number;
  $("prompt").innerHTML = state.meta.prompt_html;  // the instructor's, rendered by the desk
  renderRubric();
  renderComments();
  renderProgress({[question]: state.meta.progress});
  const linked = answers.findIndex((a) => a.id === location.hash.slice(1));
  window.addEventListener("hashchange", () => {
    const i = state.answers.findIndex((a) => a.id === location.hash.slice(1));
    if (i >= 0 && i !== state.index) {
      show(i);
    }
  });
  const first = answers.findIndex((a) => a.status === "pending");
  await show(linked >= 0 ? linked : Math.max(first, 0), true);
  desk.dataset.ready = "1";
}

start().catch((error) => say(`The desk could not load this question: ${error.message}`, true));
