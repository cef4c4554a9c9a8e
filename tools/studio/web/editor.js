// The rule file as text (Debian's CodeMirror 5, libjs-codemirror): colouring for the fmpc language and MATLAB's
// .fis, and live diagnostics exactly as `fmpc check` reports them (the server runs the same check), with "did you
// mean" suggestions and fix-its applied with a click.
"use strict";

CodeMirror.defineSimpleMode("fmpc", {
  start: [
    { regex: /#.*/, token: "comment" },
    { regex: /"[^"\n]*"?/, token: "string" },
    { regex: /\b(?:system|input|output|rule|if|then|is|not|and|or|weight|somewhat|very|extremely|interval_type2)\b/, token: "keyword" },
    { regex: /\b(?:type|implication|aggregation|defuzzify|samples|exact|when|no|fires|midrange|value|error|in|mamdani|sugeno|upper|lower|scale|lag|type_reduction)\b/, token: "builtin" },
    { regex: /\b(?:triangle|trapezoid|gauss2|gauss|bell|sigmoid|dsigmoid|psigmoid|zshape|sshape|pishape|linear_s|linear_z|constant|linear)(?=\s*\()/, token: "def" },
    { regex: /-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?/, token: "number" },
    { regex: /[A-Za-z_][A-Za-z0-9_]*/, token: "variable" },
  ],
  meta: { lineComment: "#" },
});

CodeMirror.defineSimpleMode("matlab-fis", {
  start: [
    { regex: /[%#].*/, token: "comment" },
    { regex: /^\s*\[[A-Za-z0-9]+\]/, token: "header" },
    { regex: /'[^'\n]*'?/, token: "string" },
    { regex: /^\s*[A-Za-z0-9]+(?==)/, token: "keyword" },
    { regex: /-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?/, token: "number" },
  ],
});

// A diagnostic's 1-based line and byte column as a CodeMirror position (0-based line, UTF-16 character).
Studio.position = function (line, byteColumn) {
  const text = Studio.editor.getLine(Math.max(line - 1, 0)) || "";
  let bytes = 0, ch = 0;
  const encoder = new TextEncoder();
  for (const character of text) {
    if (bytes >= byteColumn - 1) break;
    bytes += encoder.encode(character).length;
    ch += character.length;
  }
  return CodeMirror.Pos(Math.max(line - 1, 0), ch);
};

// Replaces the text between two diagnostic positions.
Studio.replaceRange = function (range, replacement) {
  Studio.editor.replaceRange(replacement, Studio.position(range.line, range.column),
    Studio.position(range.end_line, range.end_column));
};

// A suggestion a click can apply: the fix-it, or a "did you mean 'X'?" note for the diagnostic's own range.
Studio.suggestion = function (diagnostic) {
  if (diagnostic.fix) return { label: "Apply: " + diagnostic.fix.replacement, range: diagnostic.fix.range, text: diagnostic.fix.replacement };
  for (const note of diagnostic.notes) {
    const match = /^did you mean '([^']*)'\?$/.exec(note);
    if (match && diagnostic.line > 0) return { label: "Use '" + match[1] + "'", range: diagnostic, text: match[1] };
  }
  return null;
};

Studio.renderProblems = function (check) {
  const list = document.getElementById("problems");
  list.replaceChildren();
  const count = document.getElementById("problem-count");
  count.textContent = check.errors + " error" + (check.errors === 1 ? "" : "s") + ", " + check.warnings +
    " warning" + (check.warnings === 1 ? "" : "s");
  count.className = "count " + (check.errors ? "bad" : check.warnings ? "warn" : "good");
  if (!check.diagnostics.length) list.append(Studio.element("li", { class: "none", text: "No problems: fmpc check finds nothing." }));
  for (const d of check.diagnostics) {
    const where = d.line > 0 ? "line " + d.line + ", column " + d.column : "";
    const item = Studio.element("li", { class: "problem " + d.severity }, [
      Studio.element("span", { class: "where", text: where }),
      Studio.element("span", { class: "severity", text: d.severity }),
      Studio.element("span", { class: "text", text: d.message + (d.code ? " [" + d.code + "]" : "") }),
    ]);
    for (const note of d.notes) item.append(Studio.element("div", { class: "note", text: note }));
    const suggestion = Studio.suggestion(d);
    if (suggestion)
      item.append(Studio.element("button", {
        class: "fix", text: suggestion.label,
        onclick: (event) => { event.stopPropagation(); Studio.replaceRange(suggestion.range, suggestion.text); },
      }));
    if (d.line > 0)
      item.addEventListener("click", () => {
        const position = Studio.position(d.line, d.column);
        Studio.editor.focus();
        Studio.editor.setCursor(position);
        Studio.editor.scrollIntoView(position, 80);
      });
    list.append(item);
  }
};

// The lint addon's source: the server's check of the whole text.
Studio.lint = function (text, update) {
  if (!Studio.state.path) return;
  Studio.call("/api/check", { path: Studio.state.path, text: text }).then((check) => {
    if (text !== Studio.editor.getValue()) return;  // a newer text is on its way
    Studio.state.check = check;
    Studio.state.checkedText = text;
    const annotations = check.diagnostics.filter((d) => d.line > 0).map((d) => ({
      from: Studio.position(d.line, d.column),
      to: Studio.position(d.end_line || d.line, d.end_column || d.column + 1),
      severity: d.severity === "note" ? "warning" : d.severity,
      message: d.message + (d.notes.length ? "\n" + d.notes.join("\n") : ""),
    }));
    update(Studio.editor, annotations);
    Studio.renderProblems(check);
    Studio.emit("check", check);
  }).catch((error) => Studio.message(error.message, "bad"));
};

Studio.createEditor = function () {
  Studio.editor = CodeMirror(document.getElementById("editor"), {
    mode: "fmpc",
    lineNumbers: true,
    gutters: ["CodeMirror-lint-markers"],
    lint: { getAnnotations: Studio.lint, async: true, delay: 250 },
    indentUnit: 2,
    viewportMargin: 20,
  });
  Studio.editor.on("change", () => Studio.emit("text", Studio.editor.getValue()));
};

// Puts `text` in the editor, keeping the view where it was (edits from the table and the membership editor).
Studio.setText = function (text) {
  if (text === Studio.editor.getValue()) return;
  const scroll = Studio.editor.getScrollInfo();
  const cursor = Studio.editor.getCursor();
  Studio.editor.operation(() => {
    Studio.editor.setValue(text);
    Studio.editor.setCursor(cursor);
    Studio.editor.scrollTo(scroll.left, scroll.top);
  });
};

Studio.setMode = function (text) {
  const first = text.split("\n").find((line) => line.trim() && !/^\s*[%#]/.test(line)) || "";
  Studio.editor.setOption("mode", first.trim().startsWith("[System]") ? "matlab-fis" : "fmpc");
};
