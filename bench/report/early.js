/* Runs first: collects every script error, failed resource load, rejected promise and console.error, so the
   self-check at the end of the page (report.js) can report them. */
window.__icErrors = [];
window.addEventListener("error", function (e) {
  if (e.target && e.target !== window && (e.target.src || e.target.href)) {
    window.__icErrors.push("failed to load " + (e.target.src || e.target.href));
  } else {
    window.__icErrors.push(String(e.message) + (e.filename ? " at " + e.filename + ":" + e.lineno : ""));
  }
}, true);
window.addEventListener("unhandledrejection", function (e) {
  window.__icErrors.push("unhandled rejection: " + String(e.reason));
});
(function () {
  var original = console.error;
  console.error = function () {
    window.__icErrors.push("console.error: " + Array.prototype.join.call(arguments, " "));
    return original.apply(console, arguments);
  };
})();
