"use strict";
// What every page of the review desk shares: the JSON API (the same calls a script makes,
// authenticated by the desk's cookie), the status line, and when a key press is typing.

async function api(path, body) {
  const init = {credentials: "same-origin", headers: {"Accept": "application/json"}};
  if (body !== undefined) {
    init.method = "POST";
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  const response = await fetch(path, init);
  const data = await response.json().catch(() => ({error: response.statusText}));
  if (!response.ok) {
    throw new Error(data.error || `${response.status} ${response.statusText}`);
  }
  return data;
}

function say(text, error = false) {
  const status = document.getElementById("status");
  status.textContent = text;
  status.classList.toggle("error", error);
}

function typing(target) {
  // A key pressed in a text field is text, not a shortcut.
  if (target instanceof HTMLTextAreaElement || target instanceof HTMLSelectElement) {
    return true;
  }
  return target instanceof HTMLInputElement &&
    !["checkbox", "radio", "button", "submit"].includes(target.type);
}

function points(x) {
  // As the gradebook shows points: up to 4 significant figures, no exponent.
  return Number(Number(x).toPrecision(4)).toString();
}
