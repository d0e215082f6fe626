// Loaded first, as a classic script: keeps every uncaught error, rejected promise and
// console.error call in window.__dashboardErrors (read by the browser test) and shows a
// banner, so that a broken page is noticed rather than silently half-working.
(function () {
  var errors = (window.__dashboardErrors = []);
  function record(text) {
    errors.push(String(text));
    var el = document.getElementById('error-banner');
    if (el) {
      el.hidden = false;
      el.textContent = 'Something went wrong in the dashboard: ' + text;
    }
  }
  var original = console.error;
  console.error = function () {
    var parts = [];
    for (var i = 0; i < arguments.length; i++) {
      var a = arguments[i];
      parts.push(a && a.stack ? a.stack : a && typeof a === 'object' ? JSON.stringify(a) : String(a));
    }
    record(parts.join(' '));
    return original.apply(console, arguments);
  };
  window.addEventListener('error', function (ev) {
    if (ev.target && ev.target !== window && ev.target.tagName) {
      // a resource (img, script, link) failed to load
      record('failed to load ' + (ev.target.src || ev.target.href || ev.target.tagName));
    } else {
      record((ev.message || 'error') + (ev.filename ? ' at ' + ev.filename + ':' + ev.lineno : ''));
    }
  }, true);
  window.addEventListener('unhandledrejection', function (ev) {
    var r = ev.reason;
    record('unhandled rejection: ' + (r && r.stack ? r.stack : r));
  });
})();
