(function () {
  'use strict';
  var status = document.getElementById('mp-status');
  var errors = 0;
  function fail(msg) {
    errors += 1;
    status.setAttribute('data-errors', String(errors));
    status.textContent = 'error: ' + msg;
  }
  window.addEventListener('error', function (e) { fail(e.message || 'script error'); });
  window.addEventListener('unhandledrejection', function (e) { fail(String(e.reason)); });

  var D = JSON.parse(document.getElementById('mp-data').textContent);
  var FR = JSON.parse(document.getElementById('mp-frames').textContent);
  var T = D.frames, J = D.joints.length, DIM = D.dims, V = D.view;
  var KN = D.kindNames, KC = D.kindColors;
  var B = D.bounds, NS = B.length - 1;
  var cur = 0, playing = false, speed = 1, loopPlay = true, sel = D.defaultJoint;
  var showKp = true, showProg = true;

  // ---- people: the page shows one person's analysis at a time ---------------
  // PS[k]: person k's arrays (0: the main person, the page's own data);
  // OFF: the video frame of the shown person's frame 0.
  var PEOPLE = D.people || null, PK = 0, OFF = 0;
  var PS = [{ frames: D.frames, kp: D.kp, conf: D.conf, prog: D.prog, span: D.span, bounds: D.bounds,
              kinds: D.kinds, intervals: D.intervals, defaultJoint: D.defaultJoint, offset: 0 }];
  if (PEOPLE) {
    var blocks = document.querySelectorAll('script.mp-person');
    for (var bi = 0; bi < blocks.length; bi++) {
      PS[+blocks[bi].getAttribute('data-person')] = JSON.parse(blocks[bi].textContent);
    }
  }
  function inPerson(el) {
    if (!PEOPLE || !el) return el;
    return el.querySelector('.pp[data-person="' + PK + '"]') || el;
  }

  function $(id) { return document.getElementById(id); }
  function clamp(v, a, b) { return v < a ? a : (v > b ? b : v); }
  function segAt(f) {
    var lo = 0, hi = NS - 1;
    while (lo < hi) { var m = (lo + hi + 1) >> 1; if (B[m] <= f) lo = m; else hi = m - 1; }
    return lo;
  }
  function kindOf(j, s) { return +D.kinds[j].charAt(s); }

  // ---- frames -------------------------------------------------------------
  var imgs = FR.length ? FR.map(function () { return null; }) : null;
  function img(p) {
    if (!imgs) return null;
    if (!imgs[p]) {
      var im = new Image();
      im.onload = function () { if (nearest(cur) === p) { drawStage(); measureCanvas(); } };
      im.src = FR[p];
      imgs[p] = im;
    }
    return imgs[p];
  }
  function nearest(f) {
    var idx = D.frameIdx, lo = 0, hi = idx.length - 1;
    if (hi < 0) return -1;
    while (lo < hi) { var m = (lo + hi + 1) >> 1; if (idx[m] <= f) lo = m; else hi = m - 1; }
    return lo;
  }
  if (imgs) { for (var p = 0; p < FR.length; p++) img(p); }

  // ---- stage ----------------------------------------------------------------
  var stage = $('stage'), ctx = stage.getContext('2d', { willReadFrequently: false });
  var dpr = Math.min(window.devicePixelRatio || 1, 2);
  var CW = D.canvas.w, CH = D.canvas.h;
  var ds = Math.min(540 / CH, 720 / CW);
  if (!(ds > 0)) ds = 1;
  stage.width = Math.round(CW * ds * dpr);
  stage.height = Math.round(CH * ds * dpr);
  stage.style.width = Math.round(CW * ds) + 'px';
  var K = ds * dpr;
  var bg = null;
  if (!imgs) {
    bg = document.createElement('canvas');
    bg.width = stage.width; bg.height = stage.height;
    var g = bg.getContext('2d');
    g.fillStyle = '#0f172a'; g.fillRect(0, 0, bg.width, bg.height);
    g.strokeStyle = 'rgba(71,85,105,.45)'; g.lineWidth = 1;
    var step = 40 * K;
    for (var x = step; x < bg.width; x += step) { g.beginPath(); g.moveTo(x, 0); g.lineTo(x, bg.height); g.stroke(); }
    for (var y = step; y < bg.height; y += step) { g.beginPath(); g.moveTo(0, y); g.lineTo(bg.width, y); g.stroke(); }
  }
  function pt(arr, f, j) {
    var o = (f * J + j) * DIM;
    var x = arr[o], y = arr[o + 1];
    return [(x * V.scale + V.dx) * K, ((V.flip ? -y : y) * V.scale + V.dy) * K];
  }
  var SIDE = ['#ff9f1c', '#f1f5f9', '#38bdf8'];
  function drawSkel(arr, f, prog) {
    var ok = function (j) {
      if (prog) return true;
      return D.conf[f * J + j] > D.minConf;
    };
    var lw = (prog ? 2.2 : 3) * Math.max(1, K * 0.8);
    ctx.lineCap = 'round';
    var bones = D.bones;
    ctx.strokeStyle = 'rgba(15,23,42,.55)';
    ctx.lineWidth = lw + 2 * dpr;
    ctx.beginPath();
    for (var i = 0; i < bones.length; i++) {
      var a = bones[i][0], b = bones[i][1];
      if (!ok(a) || !ok(b)) continue;
      var pa = pt(arr, f, a), pb = pt(arr, f, b);
      ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]);
    }
    ctx.stroke();
    ctx.lineWidth = lw;
    for (i = 0; i < bones.length; i++) {
      a = bones[i][0]; b = bones[i][1];
      if (!ok(a) || !ok(b)) continue;
      pa = pt(arr, f, a); pb = pt(arr, f, b);
      var s = Math.sign(D.sides[a] + D.sides[b]);
      ctx.strokeStyle = prog ? '#f43f90' : SIDE[s + 1];
      ctx.beginPath(); ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]); ctx.stroke();
    }
    var r = (prog ? 2.6 : 3.4) * Math.max(1, K * 0.8);
    for (var j = 0; j < J; j++) {
      if (!ok(j)) continue;
      var q = pt(arr, f, j);
      ctx.beginPath(); ctx.arc(q[0], q[1], j === sel ? r * 1.9 : r, 0, 2 * Math.PI);
      ctx.fillStyle = prog ? '#f43f90' : (j === sel ? '#facc15' : '#f1f5f9');
      ctx.fill();
      ctx.lineWidth = 1 * dpr; ctx.strokeStyle = 'rgba(15,23,42,.8)'; ctx.stroke();
    }
  }
  // Another person at video frame F, thinner, in their overlay colour.
  function drawOther(P, F, colour) {
    var f = F - (P.offset || 0);
    if (f < 0 || f >= P.frames) return;
    ctx.lineCap = 'round';
    ctx.lineWidth = 2 * Math.max(1, K * 0.8);
    ctx.strokeStyle = colour;
    ctx.beginPath();
    for (var i = 0; i < D.bones.length; i++) {
      var a = D.bones[i][0], b = D.bones[i][1];
      if (!(P.conf[f * J + a] > D.minConf) || !(P.conf[f * J + b] > D.minConf)) continue;
      var pa = pt(P.kp, f, a), pb = pt(P.kp, f, b);
      ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]);
    }
    ctx.stroke();
  }
  function drawStage() {
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    if (imgs) {
      var im = img(nearest(cur + OFF));
      if (im && im.complete && im.naturalWidth) ctx.drawImage(im, 0, 0, stage.width, stage.height);
      else { ctx.fillStyle = '#0f172a'; ctx.fillRect(0, 0, stage.width, stage.height); }
    } else {
      ctx.drawImage(bg, 0, 0);
    }
    if (DIM >= 2) {
      if (PEOPLE && showKp) {
        for (var q = 0; q < PS.length; q++) if (q !== PK && PS[q]) drawOther(PS[q], cur + OFF, PEOPLE[q].colour || SIDE[0]);
      }
      var inSpan = !D.span || (cur >= D.span[0] && cur <= D.span[1]);
      if (showProg && inSpan) drawSkel(D.prog, cur, true);
      if (showKp) drawSkel(D.kp, cur, false);
    }
  }
  var measured = false;
  function measureCanvas() {
    if (measured) return;
    try {
      var w = stage.width, h = stage.height;
      var data = ctx.getImageData(0, 0, w, h).data;
      var n = 0, s = 0, s2 = 0;
      for (var y = 0; y < h; y += 7) for (var x = 0; x < w; x += 7) {
        var o = (y * w + x) * 4, v = 0.299 * data[o] + 0.587 * data[o + 1] + 0.114 * data[o + 2];
        n++; s += v; s2 += v * v;
      }
      var varr = n ? s2 / n - (s / n) * (s / n) : 0;
      stage.setAttribute('data-variance', varr.toFixed(1));
      if (!imgs || (imgs[nearest(cur + OFF)] && imgs[nearest(cur + OFF)].complete)) measured = true;
    } catch (e) { stage.setAttribute('data-variance', 'unreadable'); }
  }

  // ---- listing and joints ---------------------------------------------------
  var listBox = $('listing-box');
  var lists = inPerson(listBox).querySelectorAll('ol.listing');
  var jointBtns = $('joints').querySelectorAll('button');
  var activeLi = null, lastSeg = -1, lastSel = -1;
  function selectJoint(j) {
    sel = clamp(j, 0, J - 1);
    for (var i = 0; i < lists.length; i++) lists[i].hidden = (i !== sel);
    var jn = document.querySelectorAll('.jn'); for (var q = 0; q < jn.length; q++) jn[q].textContent = D.joints[sel];
    lastSeg = -1;
    drawPlotStatic();
    update();
  }
  function updateListing(s) {
    if (s === lastSeg && sel === lastSel) return;
    for (var j = 0; j < jointBtns.length; j++) {
      jointBtns[j].className = 'k-' + KN[kindOf(j, s)] + (j === sel ? ' sel' : '');
      jointBtns[j].title = D.joints[j] + ': ' + KN[kindOf(j, s)];
    }
    if (activeLi) activeLi.classList.remove('active');
    activeLi = lists[sel].querySelector('li.st[data-seg="' + s + '"]');
    if (activeLi) {
      activeLi.classList.add('active');
      var top = activeLi.offsetTop, h = activeLi.offsetHeight;
      if (top < listBox.scrollTop || top + h > listBox.scrollTop + listBox.clientHeight) {
        listBox.scrollTop = Math.max(0, top - listBox.clientHeight / 3);
      }
    }
    lastSeg = s; lastSel = sel;
  }
  for (var jb = 0; jb < jointBtns.length; jb++) {
    (function (j) { jointBtns[j].addEventListener('click', function () { selectJoint(j); }); })(jb);
  }
  listBox.addEventListener('click', function (e) {
    var li = e.target.closest ? e.target.closest('li.st') : null;
    if (li) seek(B[+li.getAttribute('data-seg')]);
  });

  // ---- timeline -------------------------------------------------------------
  var SVGNS = 'http://www.w3.org/2000/svg';
  var tl = null, tlCursor = null;
  function setupTimeline() {
    tl = inPerson($('timeline')).querySelector('svg.mp-timeline');
    if (!tl) { tlCursor = null; return; }
    if (tl.mpCursor) { tlCursor = tl.mpCursor; return; }
    tlCursor = document.createElementNS(SVGNS, 'rect');
    tlCursor.setAttribute('y', tl.getAttribute('data-top'));
    tlCursor.setAttribute('height', String(+tl.getAttribute('data-bottom') - +tl.getAttribute('data-top')));
    tlCursor.setAttribute('fill', '#facc15');
    tlCursor.setAttribute('fill-opacity', '0.9');
    tlCursor.setAttribute('stroke', '#0f172a');
    tlCursor.setAttribute('stroke-width', '0.6');
    tl.appendChild(tlCursor);
    tl.mpCursor = tlCursor;
    var svg = tl;
    svg.addEventListener('click', function (e) {
      var r = svg.getBoundingClientRect();
      var vb = svg.viewBox.baseVal;
      var x = (e.clientX - r.left) / r.width * vb.width;
      var x0 = +svg.getAttribute('data-x0'), x1 = +svg.getAttribute('data-x1');
      seek(Math.floor((x - x0) / (x1 - x0) * T));
    });
  }
  setupTimeline();
  function updateTimeline() {
    if (!tlCursor) return;
    var x0 = +tl.getAttribute('data-x0'), x1 = +tl.getAttribute('data-x1');
    var w = Math.max(2, (x1 - x0) / T);
    tlCursor.setAttribute('x', String(x0 + cur / T * (x1 - x0) + w / 2 - 1.5));
    tlCursor.setAttribute('width', '3');
  }

  // ---- loops ----------------------------------------------------------------
  var loopRows = inPerson($('repetitions')).querySelectorAll('table.loops tbody tr');
  function loopAt(f) {
    for (var i = 0; i < D.intervals.length; i++) {
      var iv = D.intervals[i];
      if (f >= iv.start && f < iv.end) {
        var it = 0;
        while (it + 1 < iv.boundaries.length - 1 && iv.boundaries[it + 1] <= f) it++;
        return [i, it];
      }
    }
    return null;
  }
  function updateLoops() {
    var L = loopAt(cur);
    var rep = $('rep');
    for (var i = 0; i < loopRows.length; i++) {
      var on = L && L[0] === i;
      loopRows[i].className = on ? 'now' : '';
      var spans = loopRows[i].querySelectorAll('.iters span');
      for (var k = 0; k < spans.length; k++) spans[k].className = (on && k === L[1]) ? 'on' : '';
    }
    if (L) {
      var iv = D.intervals[L[0]];
      rep.textContent = 'loop ' + (L[0] + 1) + ' \u00b7 repetition ' + (L[1] + 1) + ' / ' + iv.count;
      rep.className = 'rep on';
    } else { rep.className = 'rep'; }
    return L;
  }

  // ---- trajectory plot ------------------------------------------------------
  var plot = $('plot'), pctx = plot.getContext('2d');
  var plotStatic = document.createElement('canvas');
  var PL = null;
  function niceTicks(lo, hi, n) {
    var raw = (hi - lo) / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
    var stp = [1, 2, 2.5, 5, 10].map(function (m) { return m * mag; }).find(function (s) { return s >= raw; }) || 10 * mag;
    var out = [];
    for (var v = Math.ceil(lo / stp) * stp; v <= hi + stp * 1e-9 && out.length < 60; v += stp) out.push(Math.abs(v) < stp * 1e-9 ? 0 : v);
    return out;
  }
  function fmt(v) { return (Math.round(v * 100) / 100).toString(); }
  function drawPlotStatic() {
    var w = plot.clientWidth || 760, h = plot.clientHeight || 360;
    plot.width = Math.round(w * dpr); plot.height = Math.round(h * dpr);
    plotStatic.width = plot.width; plotStatic.height = plot.height;
    var g = plotStatic.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.fillStyle = '#fff'; g.fillRect(0, 0, w, h);
    var left = 58, right = 14, top = 8, gap = 14, bottom = 30;
    var ph = (h - top - bottom - gap * (DIM - 1)) / DIM;
    var x0 = left, x1 = w - right, span = Math.max(1, T - 1);
    var fx = function (f) { return x0 + f / span * (x1 - x0); };
    var panels = [];
    g.font = '11px system-ui, "DejaVu Sans", sans-serif';
    for (var k = 0; k < DIM; k++) {
      var py0 = top + k * (ph + gap), py1 = py0 + ph;
      var lo = Infinity, hi = -Infinity, f, v, j = sel;
      for (f = 0; f < T; f++) {
        if (D.conf[f * J + j] > 0) { v = D.kp[(f * J + j) * DIM + k]; if (v < lo) lo = v; if (v > hi) hi = v; }
        v = D.prog[(f * J + j) * DIM + k]; if (v < lo) lo = v; if (v > hi) hi = v;
      }
      if (!isFinite(lo) || !isFinite(hi)) { lo = 0; hi = 1; }
      if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
      var pad = 0.08 * (hi - lo); lo -= pad; hi += pad;
      var inv = (D.units === 'px' && k === 1);
      var fy = (function (lo, hi, py0, py1, inv) {
        return function (v) { var a = (v - lo) / (hi - lo); return inv ? py0 + a * (py1 - py0) : py1 - a * (py1 - py0); };
      })(lo, hi, py0, py1, inv);
      panels.push({ py0: py0, py1: py1, fy: fy, k: k });
      g.fillStyle = '#f8fafc'; g.fillRect(x0, py0, x1 - x0, ph);
      g.strokeStyle = '#cbd5e1'; g.lineWidth = 1; g.strokeRect(x0 + .5, py0 + .5, x1 - x0 - 1, ph - 1);
      for (var i = 0; i < D.intervals.length; i++) {
        var iv = D.intervals[i];
        g.fillStyle = 'rgba(20,184,166,.10)';
        g.fillRect(fx(iv.start), py0, fx(iv.end - 1) - fx(iv.start), ph);
        g.strokeStyle = 'rgba(15,118,110,.45)'; g.setLineDash([4, 3]);
        for (var bI = 0; bI < iv.boundaries.length; bI++) {
          var bx = fx(Math.min(iv.boundaries[bI], T - 1));
          g.beginPath(); g.moveTo(bx, py0); g.lineTo(bx, py1); g.stroke();
        }
        g.setLineDash([]);
      }
      var tk = niceTicks(lo, hi, 4);
      g.fillStyle = '#64748b'; g.textAlign = 'right'; g.textBaseline = 'middle';
      for (i = 0; i < tk.length; i++) {
        var ty = fy(tk[i]);
        g.strokeStyle = '#e2e8f0'; g.beginPath(); g.moveTo(x0, ty); g.lineTo(x1, ty); g.stroke();
        g.fillText(fmt(tk[i]), x0 - 6, ty);
      }
      g.save(); g.translate(14, (py0 + py1) / 2); g.rotate(-Math.PI / 2); g.textAlign = 'center';
      g.fillStyle = '#0f172a';
      g.fillText(D.axisLabels[k], 0, 0); g.restore();
      for (f = 0; f < T; f++) {
        var c = D.conf[f * J + j];
        if (c > 0) {
          g.fillStyle = 'rgba(71,85,105,' + (0.25 + 0.45 * Math.min(1, c)).toFixed(2) + ')';
          g.beginPath(); g.arc(fx(f), fy(D.kp[(f * J + j) * DIM + k]), 2.1, 0, 2 * Math.PI); g.fill();
        }
      }
      g.lineWidth = 2.4; g.lineJoin = 'round'; g.lineCap = 'round';
      for (var s = 0; s < NS; s++) {
        g.strokeStyle = KC[kindOf(j, s)]; g.fillStyle = g.strokeStyle;
        if (B[s + 1] - B[s] === 1) { g.beginPath(); g.arc(fx(B[s]), fy(D.prog[(B[s] * J + j) * DIM + k]), 2.4, 0, 2 * Math.PI); g.fill(); continue; }
        g.beginPath();
        for (f = B[s]; f < B[s + 1]; f++) {
          var yy = fy(D.prog[(f * J + j) * DIM + k]);
          if (f === B[s]) g.moveTo(fx(f), yy); else g.lineTo(fx(f), yy);
        }
        g.stroke();
      }
    }
    g.fillStyle = '#64748b'; g.textAlign = 'center'; g.textBaseline = 'top';
    var xt = niceTicks(0, span, 10);
    var last = panels[panels.length - 1];
    for (var q = 0; q < xt.length; q++) { g.fillText(fmt(xt[q]), fx(xt[q]), last.py1 + 5); }
    PL = { fx: fx, panels: panels, x0: x0, x1: x1 };
    drawPlot();
  }
  function drawPlot() {
    if (!PL) return;
    pctx.setTransform(1, 0, 0, 1, 0, 0);
    pctx.drawImage(plotStatic, 0, 0);
    pctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    var x = PL.fx(cur);
    pctx.strokeStyle = '#0f172a'; pctx.lineWidth = 1.2;
    for (var i = 0; i < PL.panels.length; i++) {
      var P = PL.panels[i];
      pctx.beginPath(); pctx.moveTo(x, P.py0); pctx.lineTo(x, P.py1); pctx.stroke();
      var v = D.prog[(cur * J + sel) * DIM + P.k];
      pctx.beginPath(); pctx.arc(x, P.fy(v), 4.5, 0, 2 * Math.PI);
      pctx.fillStyle = '#f43f90'; pctx.fill(); pctx.strokeStyle = '#fff'; pctx.lineWidth = 1.5; pctx.stroke();
      pctx.strokeStyle = '#0f172a'; pctx.lineWidth = 1.2;
    }
  }
  plot.addEventListener('click', function (e) {
    if (!PL) return;
    var r = plot.getBoundingClientRect();
    var x = e.clientX - r.left;
    seek(Math.round((x - PL.x0) / (PL.x1 - PL.x0) * (T - 1)));
  });
  window.addEventListener('resize', function () { drawPlotStatic(); });

  // ---- controls -------------------------------------------------------------
  var scrub = $('scrub'), playBtn = $('play'), readout = $('readout'), badge = $('badge');
  scrub.max = String(T - 1);
  function update() {
    var s = segAt(cur);
    drawStage();
    updateListing(s);
    updateTimeline();
    updateLoops();
    drawPlot();
    scrub.value = String(cur);
    updateStrip();
    var t = (cur + OFF) / D.fps;
    badge.textContent = 'frame ' + (cur + OFF) + ' / ' + (OFF + T - 1) + ' \u00b7 ' + t.toFixed(2) + ' s';
    readout.textContent = 'segment ' + (s + 1) + ' / ' + NS + ' (frames ' + B[s] + '\u2013' + (B[s + 1] - 1) + ') \u00b7 ' +
      D.joints[sel] + ': ' + KN[kindOf(sel, s)];
  }
  function seek(f) { cur = clamp(f | 0, 0, T - 1); update(); }
  var last = null, acc = 0;
  function tick(ts) {
    if (!playing) return;
    if (last === null) last = ts;
    acc += (ts - last) / 1000 * D.fps * speed; last = ts;
    var adv = Math.floor(acc);
    if (adv > 0) {
      acc -= adv;
      var n = cur + adv;
      if (n >= T) { if (loopPlay) n = n % T; else { n = T - 1; setPlaying(false); } }
      seek(n);
    }
    requestAnimationFrame(tick);
  }
  function setPlaying(on) {
    playing = on; playBtn.textContent = on ? '\u275a\u275a Pause' : '\u25b6 Play';
    last = null; acc = 0;
    if (on) requestAnimationFrame(tick);
  }
  playBtn.addEventListener('click', function () { setPlaying(!playing); });
  $('prev').addEventListener('click', function () { setPlaying(false); seek(cur - 1); });
  $('next').addEventListener('click', function () { setPlaying(false); seek(cur + 1); });
  scrub.addEventListener('input', function () { seek(+scrub.value); });
  $('speed').addEventListener('change', function (e) { speed = +e.target.value; });
  $('loop').addEventListener('change', function (e) { loopPlay = e.target.checked; });
  $('show-kp').addEventListener('change', function (e) { showKp = e.target.checked; drawStage(); });
  $('show-prog').addEventListener('change', function (e) { showProg = e.target.checked; drawStage(); });
  document.addEventListener('keydown', function (e) {
    if (e.target && (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT')) return;
    if (e.key === ' ') { e.preventDefault(); setPlaying(!playing); }
    else if (e.key === 'ArrowRight') { setPlaying(false); seek(cur + 1); }
    else if (e.key === 'ArrowLeft') { setPlaying(false); seek(cur - 1); }
    else if (e.key === 'Home') { seek(0); }
  });
  stage.addEventListener('click', function (e) {
    if (DIM < 2) return;
    var r = stage.getBoundingClientRect();
    var x = (e.clientX - r.left) / r.width * stage.width, y = (e.clientY - r.top) / r.height * stage.height;
    var best = -1, bd = Infinity;
    for (var j = 0; j < J; j++) {
      if (D.conf[cur * J + j] <= D.minConf) continue;
      var q = pt(D.kp, cur, j), d = (q[0] - x) * (q[0] - x) + (q[1] - y) * (q[1] - y);
      if (d < bd) { bd = d; best = j; }
    }
    if (best >= 0 && bd < Math.pow(30 * dpr, 2)) selectJoint(best);
  });

  // ---- people picker and strip -----------------------------------------------
  var strip = document.querySelector('svg.mp-people'), stripCursor = null;
  if (strip) {
    stripCursor = document.createElementNS(SVGNS, 'rect');
    stripCursor.setAttribute('y', strip.getAttribute('data-top'));
    stripCursor.setAttribute('height', String(+strip.getAttribute('data-bottom') - +strip.getAttribute('data-top')));
    stripCursor.setAttribute('width', '2');
    stripCursor.setAttribute('fill', '#0f172a');
    strip.appendChild(stripCursor);
    var rows = strip.querySelectorAll('g.row[data-person]');
    for (var ri = 0; ri < rows.length; ri++) {
      (function (g) { g.addEventListener('click', function () { pickPerson(+g.getAttribute('data-person')); }); })(rows[ri]);
    }
  }
  function updateStrip() {
    if (!stripCursor) return;
    var x0 = +strip.getAttribute('data-x0'), x1 = +strip.getAttribute('data-x1');
    stripCursor.setAttribute('x', String(x0 + (cur + OFF) / PS[0].frames * (x1 - x0) - 1));
  }
  // Shows person k's analysis (`quiet`: without redrawing, while loading).
  function pickPerson(k, quiet) {
    var P = PS[k];
    if (!P) return;
    var video = cur + OFF;
    PK = k;
    D.frames = P.frames; D.kp = P.kp; D.conf = P.conf; D.prog = P.prog; D.span = P.span;
    D.bounds = P.bounds; D.kinds = P.kinds; D.intervals = P.intervals; D.defaultJoint = P.defaultJoint;
    T = P.frames; B = P.bounds; NS = B.length - 1; OFF = P.offset || 0;
    var pps = document.querySelectorAll('.pp');
    for (var i = 0; i < pps.length; i++) pps[i].hidden = (+pps[i].getAttribute('data-person') !== k);
    lists = inPerson(listBox).querySelectorAll('ol.listing');
    activeLi = null; lastSeg = -1; lastSel = -1;
    setupTimeline();
    loopRows = inPerson($('repetitions')).querySelectorAll('table.loops tbody tr');
    scrub.max = String(T - 1);
    cur = clamp(video - OFF, 0, T - 1);
    var pick = $('person');
    if (pick) pick.value = String(k);
    var srows = strip ? strip.querySelectorAll('g.row') : [];
    for (i = 0; i < srows.length; i++) {
      srows[i].setAttribute('opacity', srows[i].getAttribute('data-person') === String(k) || !srows[i].hasAttribute('data-person') ? '1' : '0.75');
    }
    if (!quiet) selectJoint(P.defaultJoint);
    else sel = P.defaultJoint;
    status.setAttribute('data-person', String(PEOPLE ? PEOPLE[k].id : ''));
  }
  if ($('person')) $('person').addEventListener('change', function (e) { setPlaying(false); pickPerson(+e.target.value); });

  // A link may pick the person, the frame and the joint:
  // report.html#person=2&frame=120&joint=right_wrist (the frame of the video)
  var hash = {};
  (window.location.hash || '').replace(/^#/, '').split('&').forEach(function (kv) {
    var i = kv.indexOf('=');
    if (i > 0) hash[decodeURIComponent(kv.slice(0, i))] = decodeURIComponent(kv.slice(i + 1));
  });
  if (PEOPLE && hash.person) {
    for (var hp = 0; hp < PEOPLE.length; hp++) if (String(PEOPLE[hp].id) === hash.person && PS[hp]) pickPerson(hp, true);
  }
  if (hash.joint && D.joints.indexOf(hash.joint) >= 0) sel = D.joints.indexOf(hash.joint);
  if (hash.frame && isFinite(+hash.frame)) cur = clamp(Math.round(+hash.frame) - OFF, 0, T - 1);
  selectJoint(sel);
  measureCanvas();
  status.setAttribute('data-ready', '1');
  if (errors === 0) status.textContent = 'ok';
})();
