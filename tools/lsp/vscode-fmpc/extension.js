// Starts `fmpc lsp` (docs/lsp.md) for fmpc rule files and talks to it over standard input and output through
// Microsoft's vscode-languageclient. Everything the editor shows comes from the server.
const vscode = require('vscode');
const { LanguageClient } = require('vscode-languageclient/node');

let client;

function activate(context) {
  const command = vscode.workspace.getConfiguration('fmpc').get('path') || 'fmpc';
  const serverOptions = { command, args: ['lsp'] };
  const clientOptions = {
    documentSelector: [
      { scheme: 'file', language: 'fmpc' },
      { scheme: 'untitled', language: 'fmpc' },
    ],
  };
  client = new LanguageClient('fmpc', 'fmpc language server', serverOptions, clientOptions);
  context.subscriptions.push(client);
  return client.start();
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
