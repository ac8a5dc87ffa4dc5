// Runs before everything else: any error or console.error of the page is
// counted in #softrod-status[data-errors] and listed in #errors, so a
// headless browser's --dump-dom (and a person) can see it.
(function () {
  'use strict';
  var pending = [];
  // Errors raised before the body exists wait in `pending`.
  function flush() {
    var st = document.getElementById('softrod-status');
    var box = document.getElementById('errors');
    if (!st || !box) { return; }
    while (pending.length) { add(st, box, pending.shift()); }
  }
  function record(text) {
    pending.push(text);
    flush();
  }
  function add(st, box, text) {
    st.setAttribute('data-errors', String(Number(st.getAttribute('data-errors') || 0) + 1));
    var line = document.createElement('div');
    line.className = 'error-line';
    line.textContent = text;
    box.appendChild(line);
    box.hidden = false;
  }
  window.softrodReportError = record;
  window.addEventListener('error', function (e) {
    record('error: ' + (e.message || e) + (e.filename ? ' (' + e.filename + ':' + e.lineno + ')' : ''));
  });
  window.addEventListener('unhandledrejection', function (e) {
    record('unhandled rejection: ' + (e.reason && e.reason.message ? e.reason.message : e.reason));
  });
  var original = console.error;
  console.error = function () {
    record('console.error: ' + Array.prototype.map.call(arguments, String).join(' '));
    if (original) { original.apply(console, arguments); }
  };
  document.addEventListener('DOMContentLoaded', flush);
})();
