// Starts the page: the folder's files, the opened rule file, the tabs, saving.
"use strict";

Studio.showTab = function (name) {
  for (const button of document.querySelectorAll("#tabs button"))
    button.classList.toggle("active", button.dataset.tab === name);
  for (const panel of document.querySelectorAll(".panel"))
    panel.classList.toggle("active", panel.id === "panel-" + name);
  Studio.state.tab = name;
  Studio.emit("tab", name);
};

Studio.updateFileState = function () {
  const modified = Studio.editor.getValue() !== Studio.state.savedText;
  const element = document.getElementById("file-state");
  element.textContent = modified ? "modified (not saved)" : "saved";
  element.className = "state " + (modified ? "modified" : "saved");
};

Studio.openFile = async function (path) {
  const file = await Studio.call("/api/file?path=" + encodeURIComponent(path));
  Studio.state.path = file.path;
  Studio.state.version = file.version;
  Studio.state.savedText = file.text;
  Studio.state.check = null;
  Studio.setMode(file.text);
  Studio.editor.setValue(file.text);
  Studio.editor.clearHistory();
  Studio.updateFileState();
  Studio.emit("file", file);
};

Studio.save = async function () {
  try {
    const saved = await Studio.call("/api/save", { path: Studio.state.path, text: Studio.editor.getValue(), version: Studio.state.version });
    Studio.state.version = saved.version;
    Studio.state.savedText = saved.text;
    Studio.setText(saved.text);
    Studio.updateFileState();
    Studio.message("Saved " + saved.path + " in the canonical layout.", "good");
    Studio.emit("saved", saved);
  } catch (error) {
    Studio.message((error.status === 409 ? "Not saved: " : "Not saved: ") + error.message, "bad");
  }
};

Studio.on("check", (check) => {
  const label = document.getElementById("system-label");
  const select = document.getElementById("system-select");
  label.hidden = check.systems.length < 2;
  if (check.systems.length && !check.systems.some((s) => s.name === Studio.state.systemName))
    Studio.state.systemName = check.systems[0].name;
  Studio.fillSelect(select, check.systems.map((s) => s.name), Studio.state.systemName);
  const system = Studio.system();
  if (system) Studio.emit("model", system);
  else Studio.emit("broken", check);
});

Studio.on("text", () => Studio.updateFileState());

window.addEventListener("error", (event) => {
  if (event.target && (event.target.tagName === "SCRIPT" || event.target.tagName === "LINK")) {
    const banner = document.getElementById("load-problem");
    banner.hidden = false;
    banner.textContent = "A part of the page could not be loaded (" + (event.target.src || event.target.href) +
      "): install Debian's libjs-codemirror, libjs-d3 and libjs-three, then reload.";
  }
}, true);

document.addEventListener("DOMContentLoaded", async () => {
  Studio.createEditor();
  for (const button of document.querySelectorAll("#tabs button"))
    button.addEventListener("click", () => Studio.showTab(button.dataset.tab));
  document.getElementById("save-button").addEventListener("click", Studio.save);
  document.getElementById("system-select").addEventListener("change", (event) => {
    Studio.state.systemName = event.target.value;
    Studio.emit("model", Studio.system());
  });
  document.getElementById("file-select").addEventListener("change", (event) => {
    if (Studio.editor.getValue() !== Studio.state.savedText &&
        !window.confirm("The file has changes that are not saved. Open another file and lose them?")) {
      event.target.value = Studio.state.path;
      return;
    }
    Studio.openFile(event.target.value).catch((error) => Studio.message(error.message, "bad"));
  });
  window.addEventListener("beforeunload", (event) => {
    if (Studio.editor.getValue() !== Studio.state.savedText) event.preventDefault();
  });
  try {
    const session = await Studio.call("/api/session");
    Studio.state.folder = session.folder;
    Studio.state.files = session.files;
    const rules = session.files.filter((f) => /\.(fis|fll|fcl)$/.test(f));
    Studio.fillSelect(document.getElementById("file-select"), rules, session.opened);
    Studio.emit("session", session);
    if (session.opened) await Studio.openFile(session.opened);
    else Studio.message("No rule file in this folder: start fmpc studio with a .fis file or its folder.", "bad");
  } catch (error) {
    Studio.message(error.message, "bad");
  }
});
