"use strict";
// The answers the grader flagged for a look, and overrides from there.

const $ = (id) => document.getElementById(id);
let chosen = null;

function shown(value) {
  const text = value === null || value === undefined ? "not set" : JSON.stringify(value);
  return text.length > 120 ? `${text.slice(0, 119)}…` : text;
}

function cell(row, text, tag = "td") {
  const c = document.createElement(tag);
  if (tag === "th") {
    c.scope = "row";
  }
  c.textContent = text;
  row.append(c);
  return c;
}

function overridden(o) {
  return o ? `${points(o.points)} (was ${points(o.was)}): ${o.reason}` : "";
}

function flagRow(f) {
  const row = document.createElement("tr");
  cell(row, `${f.question}`);
  cell(row, f.variable, "th");
  cell(row, f.student);
  cell(row, f.why);
  cell(row, f.message).className = "message";
  cell(row, shown(f.submitted)).className = "value";
  cell(row, shown(f.key)).className = "value";
  cell(row, `${points(f.points)} / ${points(f.max)}`);
  cell(row, overridden(f.overridden));
  const button = document.createElement("button");
  button.type = "button";
  button.textContent = "Override";
  button.setAttribute("aria-label", `Override ${f.student}'s ${f.variable}`);
  button.addEventListener("click", () => choose(f));
  cell(row, "").append(button);
  return row;
}

async function load() {
  const rows = await api("/api/flagged");
  $("flagged").tBodies[0].replaceChildren(...rows.map(flagRow));
  $("count").textContent = `${rows.length} answer${rows.length === 1 ? "" : "s"} flagged.`;
}

function choose(f) {
  chosen = f;
  $("override").hidden = false;
  $("override-what").textContent = `${f.student}'s ${f.variable} (question ${f.question}): ` +
    `${points(f.points)} of ${points(f.max)} points now; ${f.why}.`;
  $("override-points").max = f.max;
  $("override-points").value = f.overridden ? f.overridden.points : f.points;
  $("override-reason").value = f.overridden ? f.overridden.reason : "";
  $("override-remove").hidden = !f.overridden;
  $("override-points").focus();
}

function close() {
  $("override").hidden = true;
  chosen = null;
}

async function send(remove) {
  if (!chosen) {
    return;
  }
  const body = {student: chosen.student, answer: chosen.variable, remove,
    reason: $("override-reason").value};
  if (!remove) {
    body.points = Number($("override-points").value);
  }
  try {
    const result = await api("/api/override", body);
    say(`${remove ? "Removed the override of" : "Overrode"} ${chosen.student}'s ` +
        `${chosen.variable}: their total is now ${points(result.points)} points.`);
    close();
    await load();
  } catch (error) {
    say(`Not changed: ${error.message}`, true);
  }
}

$("override").addEventListener("submit", (event) => { event.preventDefault(); send(false); });
$("override-remove").addEventListener("click", () => send(true));
$("override-cancel").addEventListener("click", close);
document.addEventListener("keydown", (event) => {
  if (event.key === "Escape" && !$("override").hidden) {
    close();
  }
});
load().catch((error) => say(`The desk could not load the flagged answers: ${error.message}`,
  true));
