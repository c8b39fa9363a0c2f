/* Record overlays (hover a record: position, radius, a) and the page's self-check. Record lists come from
   the <out>/<scene>/<tag>.records.js scripts bench/run writes (window.IC_RECORDS[key]); see page.py. */
(function () {
  "use strict";

  function recordAt(rec, i) {
    var o = {}, f = rec.fields, n = f.length;
    for (var k = 0; k < n; ++k) o[f[k]] = rec.data[i * n + k];
    return o;
  }

  /* The record under image pixel (x, y): the nearest centre among visible records whose influence circle
     holds the point, else the nearest centre within 3 pixels; -1 if none. */
  function pick(rec, x, y) {
    var n = rec.fields.length, d = rec.data, best = -1, bestD = Infinity;
    for (var i = 0; i < rec.count; ++i) {
      if (!d[i * n + 8]) continue;
      var dx = d[i * n] - x, dy = d[i * n + 1] - y, dist = Math.sqrt(dx * dx + dy * dy);
      var reach = Math.max(d[i * n + 2], 3);
      if (dist <= reach && dist < bestD) { best = i; bestD = dist; }
    }
    return best;
  }

  function setupOverlay(div) {
    var rec = (window.IC_RECORDS || {})[div.dataset.key];
    var canvas = div.querySelector("canvas"), tip = div.querySelector(".tip");
    var box = div.parentNode.querySelector(".show-all");
    if (!rec || !canvas) return null;
    var ctx = canvas.getContext("2d");
    var sx = canvas.width / rec.width, sy = canvas.height / rec.height;

    function circle(r, colour, width) {
      ctx.strokeStyle = colour; ctx.lineWidth = width;
      ctx.beginPath(); ctx.arc(r.px * sx, r.py * sy, Math.max(r.radius_px * sx, 1.5), 0, 2 * Math.PI); ctx.stroke();
    }
    function drawAll() {
      ctx.clearRect(0, 0, canvas.width, canvas.height);
      if (box && box.checked) {
        var n = rec.fields.length;
        for (var i = 0; i < rec.count; ++i) if (rec.data[i * n + 8]) circle(recordAt(rec, i), "rgba(255,255,0,.35)", 1);
      }
    }
    function show(clientX, clientY) {
      var r = canvas.getBoundingClientRect();
      var x = (clientX - r.left) / r.width * rec.width, y = (clientY - r.top) / r.height * rec.height;
      var i = pick(rec, x, y);
      drawAll();
      if (i < 0) { tip.hidden = true; tip.textContent = ""; return -1; }
      var c = recordAt(rec, i);
      circle(c, "#ff00ff", 2);
      ctx.fillStyle = "#ff00ff"; ctx.fillRect(c.px * sx - 2, c.py * sy - 2, 4, 4);
      tip.textContent = "record " + i + " of " + rec.count + "\nposition (" + c.x.toPrecision(4) + ", " +
        c.y.toPrecision(4) + ", " + c.z.toPrecision(4) + ")\nradius " + c.radius.toPrecision(4) +
        " (" + c.radius_px.toFixed(1) + " px on screen)\na " + c.a + "\npixel (" + c.px.toFixed(1) + ", " +
        c.py.toFixed(1) + ")";
      tip.hidden = false;
      tip.style.left = Math.min(c.px * sx + 12, canvas.width - 10) + "px";
      tip.style.top = (c.py * sy + 12) + "px";
      return i;
    }
    canvas.addEventListener("pointermove", function (e) { show(e.clientX, e.clientY); });
    canvas.addEventListener("pointerleave", function () { tip.hidden = true; drawAll(); });
    if (box) box.addEventListener("change", drawAll);
    return { rec: rec, canvas: canvas, tip: tip, show: show };
  }

  function selfCheck(overlays) {
    var status = { images: 0, broken_images: [], plots: 0, empty_plots: 0, overlays: 0, hover_checked: 0,
                   hover_failed: [], errors: [] };
    var imgs = document.images;
    status.images = imgs.length;
    for (var i = 0; i < imgs.length; ++i)
      if (!(imgs[i].complete && imgs[i].naturalWidth > 0)) status.broken_images.push(imgs[i].getAttribute("src"));
    var plots = document.querySelectorAll("svg.plot");
    status.plots = plots.length;
    for (var p = 0; p < plots.length; ++p) {
      var series = plots[p].querySelectorAll("path.series"), ok = series.length > 0;
      for (var s = 0; s < series.length; ++s) if (!/^M[\d.]+ [\d.]+/.test(series[s].getAttribute("d") || "")) ok = false;
      if (!ok) status.empty_plots++;
    }
    status.overlays = document.querySelectorAll(".overlay").length;
    overlays.forEach(function (o, k) {
      var n = o.rec.fields.length, target = -1;
      for (var i = 0; i < o.rec.count; ++i) if (o.rec.data[i * n + 8]) { target = i; break; }
      if (target < 0) return;
      var r = o.canvas.getBoundingClientRect(), c = recordAt(o.rec, target);
      var ev = new PointerEvent("pointermove", { bubbles: true,
        clientX: r.left + c.px * r.width / o.rec.width, clientY: r.top + c.py * r.height / o.rec.height });
      o.canvas.dispatchEvent(ev);
      status.hover_checked++;
      if (o.tip.hidden || o.tip.textContent.indexOf("radius") < 0) status.hover_failed.push(k);
      o.canvas.dispatchEvent(new PointerEvent("pointerleave"));
    });
    status.errors = (window.__icErrors || []).slice();
    var pass = status.images > 0 && status.broken_images.length === 0 && status.plots > 0 &&
      status.empty_plots === 0 && status.hover_failed.length === 0 && status.errors.length === 0;
    var el = document.getElementById("selftest");
    el.textContent = (pass ? "PASS " : "FAIL ") + JSON.stringify(status);
    el.setAttribute("data-status", pass ? "pass" : "fail");
  }

  window.addEventListener("load", function () {
    var overlays = [];
    var divs = document.querySelectorAll(".overlay");
    for (var i = 0; i < divs.length; ++i) {
      var o = setupOverlay(divs[i]);
      if (o) overlays.push(o);
    }
    selfCheck(overlays);
  });
})();
