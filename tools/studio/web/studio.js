// The studio's shared state and its calls to fmpc's server. Every number the page shows comes from the server
// (fmpc's library); the page draws and asks.
"use strict";

const Studio = {
  token: document.querySelector('meta[name="fmpc-token"]').content,
  state: {
    folder: "",
    files: [],
    path: "",          // the rule file, relative to the opened folder
    version: "",       // the hash of its bytes on disk when read or saved
    savedText: "",     // the text on disk
    check: null,       // the last /api/check answer for the editor's text
    checkedText: null, // the text that answer is for
    systemName: "",
    patient: [],       // the patient panel's input values, shared by the surface and the scene
  },
  listeners: {},
};

Studio.on = function (event, listener) {
  (Studio.listeners[event] = Studio.listeners[event] || []).push(listener);
};

Studio.emit = function (event, data) {
  for (const listener of Studio.listeners[event] || []) listener(data);
};

// A call to the server. The session token goes in a header; errors come back as {"error": message}.
Studio.call = async function (path, body) {
  const options = { method: body === undefined ? "GET" : "POST", headers: { "X-Fmpc-Token": Studio.token } };
  if (body !== undefined) {
    options.headers["Content-Type"] = "application/json";
    options.body = JSON.stringify(body);
  }
  const response = await fetch(path, options);
  const answer = await response.json();
  if (!response.ok) {
    const error = new Error(answer.error || ("the server answered " + response.status));
    error.status = response.status;
    throw error;
  }
  return answer;
};

// The system the page works on, from the last check (null while the text has errors).
Studio.system = function () {
  const check = Studio.state.check;
  if (!check || !check.systems.length) return null;
  return check.systems.find((s) => s.name === Studio.state.systemName) || check.systems[0];
};

// What every request about the rules carries: the editor's text, named by its file.
Studio.rulesRequest = function (extra) {
  return Object.assign({ path: Studio.state.path, text: Studio.editor.getValue(), system: Studio.state.systemName }, extra);
};

// A line in the top bar; it goes after 12 seconds unless another replaced it.
Studio.message = function (text, kind) {
  const element = document.getElementById("message");
  element.textContent = text;
  element.className = kind || "";
  clearTimeout(Studio.messageTimer);
  if (text) Studio.messageTimer = setTimeout(() => { if (element.textContent === text) element.textContent = ""; }, 12000);
};

// At most one request of a kind in flight; while one runs, only the newest of the requests made meanwhile follows.
Studio.latest = function (run) {
  let running = false;
  let pending = null;
  const next = async function () {
    if (running || pending === null) return;
    const argument = pending;
    pending = null;
    running = true;
    try {
      await run(argument);
    } finally {
      running = false;
      next();
    }
  };
  return function (argument) {
    pending = argument === undefined ? true : argument;
    next();
  };
};

// Four significant digits, as `fmpc eval --summary` prints them.
Studio.four = function (value) {
  if (value === null || value === undefined || Number.isNaN(value)) return "nan";
  return Number(value.toPrecision(4)).toString();
};

Studio.withUnit = function (text, unit) {
  return unit && unit !== "dimensionless" ? text + " " + unit : text;
};

Studio.element = function (tag, attributes, children) {
  const element = document.createElement(tag);
  for (const [key, value] of Object.entries(attributes || {})) {
    if (key === "text") element.textContent = value;
    else if (key === "class") element.className = value;
    else if (key.startsWith("on")) element.addEventListener(key.slice(2), value);
    else element.setAttribute(key, value);
  }
  for (const child of children || []) element.append(child);
  return element;
};

Studio.fillSelect = function (select, options, selected) {
  select.replaceChildren();
  for (const option of options) {
    const value = typeof option === "string" ? option : option.value;
    const label = typeof option === "string" ? option : option.label;
    const element = Studio.element("option", { value: value, text: label });
    if (value === selected) element.selected = true;
    select.append(element);
  }
};
