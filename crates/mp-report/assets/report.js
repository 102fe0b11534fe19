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
  var J = D.joints.length, DIM = D.dims, V = D.view;
  var KN = D.kindNames, KC = D.kindColors;
  var PEOPLE = D.people, MANY = PEOPLE.length > 1;
  var PIC = D.pictures;
  var cur = 0, playing = false, speed = 1, loopPlay = true, sel = 0;
  var showKp = true, showProg = true;

  function $(id) { return document.getElementById(id); }
  function clamp(v, a, b) { return v < a ? a : (v > b ? b : v); }
  function pad(n, w) { var s = String(n); while (s.length < w) s = '0' + s; return s; }
  function esc(s) { return String(s).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;').replace(/"/g, '&quot;'); }
  // Frames first..end-1 as mp_geom::frames_label writes them (inclusive).
  function framesLabel(a, end) { var last = Math.max(end - 1, a); return last === a ? String(a) : a + '\u2013' + last; }

  // ---- loading: the files beside the page register themselves ---------------
  // A file report/… is a script calling mpReport(kind, key, content); the
  // page adds it with <script src>, which loads from disk as well.
  var REG = {}, WAIT = {}, pending = 0, ready = false;
  window.mpReport = function (kind, key, content) { REG[kind + ' ' + key] = content; };
  function settle() {
    status.setAttribute('data-pending', String(pending));
    if (!ready && pending === 0) finishLoading();
  }
  // Calls cb(content) once the file is there (at once when it already is).
  function need(kind, key, url, cb) {
    var id = kind + ' ' + key;
    if (REG[id] !== undefined) { if (cb) cb(REG[id]); return; }
    if (WAIT[id]) { if (cb) WAIT[id].push(cb); return; }
    WAIT[id] = cb ? [cb] : [];
    pending++;
    var s = document.createElement('script');
    s.src = D.base + url;
    s.async = true;
    s.onload = function () {
      var list = WAIT[id]; delete WAIT[id];
      if (s.parentNode) s.parentNode.removeChild(s);
      pending--;
      if (REG[id] === undefined) fail('no ' + kind + ' in ' + url);
      else for (var i = 0; i < list.length; i++) list[i](REG[id]);
      settle();
    };
    s.onerror = function () {
      delete WAIT[id];
      pending--;
      fail('cannot load ' + D.base + url);
      settle();
    };
    document.head.appendChild(s);
  }
  // Numbers packed by the report (mp_report::page::data::pack): base64 of
  // zigzag LEB128 differences from the same slot of the previous frame.
  function unpack(text, slots, q) {
    var b = atob(text), out = [], prev = new Float64Array(slots), k = 0, i = 0;
    while (i < b.length) {
      var x = 0, m = 1, c;
      do { c = b.charCodeAt(i++); x += (c & 127) * m; m *= 128; } while (c & 128);
      var d = (x % 2) ? -(x + 1) / 2 : x / 2;
      var slot = k % slots;
      prev[slot] += d;
      out.push(prev[slot] * q);
      k++;
    }
    return Float32Array.from(out);
  }
  var Q = D.units === 'px' ? 0.1 : 1e-4;

  // ---- people: the page shows one person's analysis at a time ---------------
  // PK: the shown person; P: their structure (person.js); T: their frames;
  // OFF: the video frame of their frame 0.
  var PK = 0, P = null, T = PEOPLE[0].frames, OFF = 0, B = [0, T], NS = 1;
  var PERSON = [];
  function hasProgram() { return !!(P && P.bounds); }
  function segAt(f) {
    var lo = 0, hi = NS - 1;
    while (lo < hi) { var m = (lo + hi + 1) >> 1; if (B[m] <= f) lo = m; else hi = m - 1; }
    return lo;
  }
  function kindOf(j, s) { return +P.kinds[j].charAt(s); }

  // ---- per-frame data: chunks of keypoints, confidences, executed program ---
  var CH = {}, chOrder = [], CHUNK = D.chunk, STRIDE = D.stride, KEEP = 24;
  function chunkKey(k, c) { return k + '/' + c; }
  function loadChunk(k, c, cb) {
    var key = chunkKey(k, c);
    if (CH[key]) { if (cb) cb(); return; }
    need('chunk', key, 'p' + k + '/data-' + pad(c, 4) + '.js', function (raw) {
      if (!CH[key]) {
        CH[key] = { kp: unpack(raw.kp, J * DIM, Q), conf: unpack(raw.conf, J, 0.01), prog: unpack(raw.prog, J * DIM, Q) };
        delete REG['chunk ' + key];
        chOrder.push(key);
        while (chOrder.length > KEEP) { var old = chOrder.shift(); delete CH[old]; }
      }
      if (cb) cb();
    });
  }
  // Person k's data at their frame f: {C: chunk, i: data frame in it}, or
  // null while it loads (it is asked for, and the stage redrawn on arrival).
  function at(k, f) {
    var M = PEOPLE[k];
    if (!M.chunks || f < 0 || f >= M.frames) return null;
    var df = Math.floor(f / STRIDE), c = Math.floor(df / CHUNK), key = chunkKey(k, c);
    var C = CH[key];
    if (!C) { loadChunk(k, c, function () { drawStage(); drawPlot(); }); return null; }
    return { C: C, i: df - c * CHUNK };
  }
  function prefetch() {
    if (!PEOPLE[PK].chunks) return;
    var df = Math.floor(cur / STRIDE), c = Math.floor(df / CHUNK);
    if (df - c * CHUNK > CHUNK / 2 && (c + 1) * CHUNK * STRIDE < T) loadChunk(PK, c + 1);
  }

  // ---- frames: JPEG files shown in an <img> under the skeleton canvas -------
  var picBox = $('picture'), stage = $('stage');
  var IM = {}, imOrder = [], shownPic = -1, wantPic = -1;
  function nearestPic(f) {
    var lo = 0, hi = PIC.length - 1;
    if (hi < 0) return -1;
    while (lo < hi) { var m = (lo + hi + 1) >> 1; if (PIC[m] <= f) lo = m; else hi = m - 1; }
    return lo;
  }
  function image(p) {
    var im = IM[p];
    if (im) return im;
    im = new Image();
    im.alt = 'frame ' + PIC[p];
    im.decoding = 'async';
    pending++;
    im.onload = function () { im.mpDone = true; pending--; if (wantPic === p) showPicture(); settle(); };
    im.onerror = function () { im.mpDone = true; pending--; fail('cannot load the picture of frame ' + PIC[p]); settle(); };
    im.src = D.base + 'frames/' + pad(PIC[p], 6) + '.jpg';
    IM[p] = im;
    imOrder.push(p);
    // At most 90 pictures are kept: the oldest asked for go first.
    if (imOrder.length > 90) {
      for (var q = 0; q < imOrder.length; q++) {
        var old = imOrder[q];
        if (old !== shownPic && old !== wantPic && old !== p && IM[old].mpDone) {
          imOrder.splice(q, 1); delete IM[old]; break;
        }
      }
    }
    return im;
  }
  function showPicture() {
    if (!PIC.length) return;
    var p = nearestPic(cur + OFF);
    wantPic = p;
    var im = image(p);
    if (p !== shownPic && im.complete && im.naturalWidth) {
      picBox.replaceChildren(im);
      shownPic = p;
      stage.setAttribute('data-picture', String(PIC[p]));
    }
    // While playing, the next pictures are asked for ahead of time.
    if (playing) for (var a = 1; a <= 6 && p + a < PIC.length; a++) image(p + a);
  }

  // ---- stage ----------------------------------------------------------------
  var ctx = stage.getContext('2d');
  var dpr = Math.min(window.devicePixelRatio || 1, 2);
  var CW = D.canvas.w, CH2 = D.canvas.h;
  var ds = Math.min(540 / CH2, 720 / CW);
  if (!(ds > 0)) ds = 1;
  stage.width = Math.round(CW * ds * dpr);
  stage.height = Math.round(CH2 * ds * dpr);
  stage.style.width = Math.round(CW * ds) + 'px';
  var K = ds * dpr;
  var bg = null;
  if (!PIC.length) {
    bg = document.createElement('canvas');
    bg.width = stage.width; bg.height = stage.height;
    var g0 = bg.getContext('2d');
    g0.fillStyle = '#0f172a'; g0.fillRect(0, 0, bg.width, bg.height);
    g0.strokeStyle = 'rgba(71,85,105,.45)'; g0.lineWidth = 1;
    var step = 40 * K;
    for (var x = step; x < bg.width; x += step) { g0.beginPath(); g0.moveTo(x, 0); g0.lineTo(x, bg.height); g0.stroke(); }
    for (var y = step; y < bg.height; y += step) { g0.beginPath(); g0.moveTo(0, y); g0.lineTo(bg.width, y); g0.stroke(); }
  }
  function pt(arr, i, j) {
    var o = (i * J + j) * DIM;
    var x = arr[o], y = arr[o + 1];
    return [(x * V.scale + V.dx) * K, ((V.flip ? -y : y) * V.scale + V.dy) * K];
  }
  var SIDE = ['#ff9f1c', '#f1f5f9', '#38bdf8'];
  function drawSkel(A, prog) {
    var C = A.C, i = A.i, arr = prog ? C.prog : C.kp;
    var ok = function (j) { return prog || C.conf[i * J + j] > D.minConf; };
    var lw = (prog ? 2.2 : 3) * Math.max(1, K * 0.8);
    ctx.lineCap = 'round';
    var bones = D.bones, a, b, pa, pb, bi;
    ctx.strokeStyle = 'rgba(15,23,42,.55)';
    ctx.lineWidth = lw + 2 * dpr;
    ctx.beginPath();
    for (bi = 0; bi < bones.length; bi++) {
      a = bones[bi][0]; b = bones[bi][1];
      if (!ok(a) || !ok(b)) continue;
      pa = pt(arr, i, a); pb = pt(arr, i, b);
      ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]);
    }
    ctx.stroke();
    ctx.lineWidth = lw;
    for (bi = 0; bi < bones.length; bi++) {
      a = bones[bi][0]; b = bones[bi][1];
      if (!ok(a) || !ok(b)) continue;
      pa = pt(arr, i, a); pb = pt(arr, i, b);
      var s = Math.sign(D.sides[a] + D.sides[b]);
      ctx.strokeStyle = prog ? '#f43f90' : SIDE[s + 1];
      ctx.beginPath(); ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]); ctx.stroke();
    }
    var r = (prog ? 2.6 : 3.4) * Math.max(1, K * 0.8);
    for (var j = 0; j < J; j++) {
      if (!ok(j)) continue;
      var q = pt(arr, i, j);
      ctx.beginPath(); ctx.arc(q[0], q[1], j === sel ? r * 1.9 : r, 0, 2 * Math.PI);
      ctx.fillStyle = prog ? '#f43f90' : (j === sel ? '#facc15' : '#f1f5f9');
      ctx.fill();
      ctx.lineWidth = 1 * dpr; ctx.strokeStyle = 'rgba(15,23,42,.8)'; ctx.stroke();
    }
  }
  // Another person at video frame F, thinner, in their overlay colour.
  function drawOther(k, F) {
    var A = at(k, F - PEOPLE[k].offset);
    if (!A) return;
    var C = A.C, i = A.i;
    ctx.lineCap = 'round';
    ctx.lineWidth = 2 * Math.max(1, K * 0.8);
    ctx.strokeStyle = PEOPLE[k].colour || SIDE[0];
    ctx.beginPath();
    for (var bi = 0; bi < D.bones.length; bi++) {
      var a = D.bones[bi][0], b = D.bones[bi][1];
      if (!(C.conf[i * J + a] > D.minConf) || !(C.conf[i * J + b] > D.minConf)) continue;
      var pa = pt(C.kp, i, a), pb = pt(C.kp, i, b);
      ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]);
    }
    ctx.stroke();
  }
  function drawStage() {
    showPicture();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, stage.width, stage.height);
    if (bg) ctx.drawImage(bg, 0, 0);
    if (DIM < 2) return;
    if (MANY && showKp) {
      for (var q = 0; q < PEOPLE.length; q++) if (q !== PK && PEOPLE[q].chunks) drawOther(q, cur + OFF);
    }
    var A = at(PK, cur);
    if (!A) return;
    var inSpan = !P || !P.span || (cur >= P.span[0] && cur <= P.span[1]);
    if (showProg && inSpan) drawSkel(A, true);
    if (showKp) drawSkel(A, false);
    stage.setAttribute('data-drawn', String(cur + OFF));
  }
  // For the browser test: how much of the canvas the skeletons (or, without
  // frames, the background) painted.
  function measureCanvas() {
    try {
      var w = stage.width, h = stage.height;
      var px = ctx.getImageData(0, 0, w, h).data;
      var n = 0;
      for (var o = 3; o < px.length; o += 4) if (px[o] > 0) n++;
      stage.setAttribute('data-ink', String(n));
    } catch (e) { stage.setAttribute('data-ink', 'unreadable'); }
  }

  // ---- listing and joints ---------------------------------------------------
  var listBox = $('listing-box');
  var jointBtns = $('joints') ? $('joints').querySelectorAll('button') : [];
  var activeLi = null, lastSeg = -1, lastSel = -1, listed = '';
  // The listing holds at most LIST_WINDOW statements around the running one
  // (a shorter program's every statement) and moves along as the page plays.
  var LIST_WINDOW = 400, listJF = null, listLo = 0, listHi = 0;
  function jointFile(k, j, cb) { need('joint', k + '/' + j, 'p' + k + '/joint-' + pad(j, 2) + '.js', cb); }
  function renderListing(at) {
    var j = sel, L = listJF.listing, n = L.length, lo = 0, hi = n;
    if (n > LIST_WINDOW) { lo = clamp(at - (LIST_WINDOW >> 1), 0, n - LIST_WINDOW); hi = lo + LIST_WINDOW; }
    var h = ['<ol class="listing"><li class="jh">joint "' + esc(D.joints[j]) + '" {</li>'];
    if (lo > 0) {
      h.push('<li class="more" data-seg="' + (lo - 1) + '">\u22ef ' + lo + ' statements before (frames ' +
        framesLabel(B[0] + OFF, B[lo] + OFF) + ')</li>');
    }
    for (var s = lo; s < hi; s++) {
      var st = L[s], p = st.indexOf('(');
      if (p < 0) p = st.length;
      h.push('<li class="st k-' + KN[kindOf(j, s)] + '" data-seg="' + s + '"><span class="fr">' +
        framesLabel(B[s] + OFF, B[s + 1] + OFF) + '</span><code><span class="fn">' + esc(st.slice(0, p)) +
        '</span>' + esc(st.slice(p)) + '</code></li>');
    }
    if (hi < n) {
      h.push('<li class="more" data-seg="' + hi + '">\u22ef ' + (n - hi) + ' statements after (frames ' +
        framesLabel(B[hi] + OFF, B[n] + OFF) + ')</li>');
    }
    h.push('<li class="jt">}</li></ol>');
    listBox.innerHTML = h.join('');
    // The frames column as wide as the longest range ("99940–99951").
    listBox.style.setProperty('--fr', (String(OFF + T).length * 2 + 2) + 'ch');
    listLo = lo; listHi = hi; activeLi = null;
  }
  function showListing() {
    if (!listBox || !hasProgram()) return;
    var key = PK + '/' + sel;
    if (listed === key) return;
    var k = PK, j = sel;
    jointFile(k, j, function (JF) {
      if (k !== PK || j !== sel || listed === key) return;
      listJF = JF;
      renderListing(segAt(cur));
      listed = key; lastSeg = -1;
      drawPlotStatic();
      update();
    });
  }
  function selectJoint(j) {
    sel = clamp(j, 0, J - 1);
    var jn = document.querySelectorAll('.jn'); for (var q = 0; q < jn.length; q++) jn[q].textContent = D.joints[sel];
    lastSeg = -1;
    showListing();
    drawPlotStatic();
    update();
  }
  function updateListing(s) {
    if (!hasProgram() || (s === lastSeg && sel === lastSel)) return;
    for (var j = 0; j < jointBtns.length; j++) {
      jointBtns[j].className = 'k-' + KN[kindOf(j, s)] + (j === sel ? ' sel' : '');
      jointBtns[j].title = D.joints[j] + ': ' + KN[kindOf(j, s)];
    }
    if (listed !== PK + '/' + sel) return;
    var n = listJF.listing.length;
    if (s < listLo || s >= listHi || (listLo > 0 && s < listLo + 40) || (listHi < n && s >= listHi - 40)) {
      renderListing(s);
    }
    if (activeLi) activeLi.classList.remove('active');
    activeLi = listBox.querySelector('li.st[data-seg="' + s + '"]');
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
  if (listBox) {
    listBox.addEventListener('click', function (e) {
      var li = e.target.closest ? e.target.closest('li.st, li.more') : null;
      if (li) seek(B[+li.getAttribute('data-seg')]);
    });
  }

  // ---- timeline -------------------------------------------------------------
  var SVGNS = 'http://www.w3.org/2000/svg';
  var tl = null, tlCursor = null;
  function setupTimeline() {
    tl = $('timeline-body') ? $('timeline-body').querySelector('svg.mp-timeline') : null;
    if (!tl) { tlCursor = null; return; }
    tlCursor = document.createElementNS(SVGNS, 'rect');
    tlCursor.setAttribute('y', tl.getAttribute('data-top'));
    tlCursor.setAttribute('height', String(+tl.getAttribute('data-bottom') - +tl.getAttribute('data-top')));
    tlCursor.setAttribute('fill', '#facc15');
    tlCursor.setAttribute('fill-opacity', '0.9');
    tlCursor.setAttribute('stroke', '#0f172a');
    tlCursor.setAttribute('stroke-width', '0.6');
    tl.appendChild(tlCursor);
    var svg = tl;
    svg.addEventListener('click', function (e) {
      var r = svg.getBoundingClientRect();
      var vb = svg.viewBox.baseVal;
      var x = (e.clientX - r.left) / r.width * vb.width;
      var x0 = +svg.getAttribute('data-x0'), x1 = +svg.getAttribute('data-x1');
      seek(Math.floor((x - x0) / (x1 - x0) * T));
    });
  }
  function updateTimeline() {
    if (!tlCursor) return;
    var x0 = +tl.getAttribute('data-x0'), x1 = +tl.getAttribute('data-x1');
    var w = Math.max(2, (x1 - x0) / T);
    tlCursor.setAttribute('x', String(x0 + cur / T * (x1 - x0) + w / 2 - 1.5));
    tlCursor.setAttribute('width', '3');
  }

  // ---- counted repetitions --------------------------------------------------
  var repRows = [], lastRep = '';
  function repAt(f) {
    var R = P ? P.repetitions : [];
    var lo = 0, hi = R.length - 1;
    while (lo <= hi) {
      var m = (lo + hi) >> 1, iv = R[m];
      if (f < iv.start) hi = m - 1;
      else if (f >= iv.end) lo = m + 1;
      else {
        var it = 0;
        while (it + 1 < iv.boundaries.length - 1 && iv.boundaries[it + 1] <= f) it++;
        return [m, it];
      }
    }
    return null;
  }
  function updateRepetitions() {
    var L = repAt(cur), key = L ? L[0] + ':' + L[1] : '';
    if (key === lastRep) return;
    var prev = lastRep ? lastRep.split(':') : null;
    lastRep = key;
    if (prev && repRows[+prev[0]]) {
      repRows[+prev[0]].className = '';
      var ps = repRows[+prev[0]].querySelectorAll('.iters span');
      if (ps[+prev[1]]) ps[+prev[1]].className = '';
    }
    var rep = $('rep');
    if (L) {
      var iv = P.repetitions[L[0]];
      if (repRows[L[0]]) {
        repRows[L[0]].className = 'now';
        var sp = repRows[L[0]].querySelectorAll('.iters span');
        if (sp[L[1]]) sp[L[1]].className = 'on';
      }
      rep.textContent = 'repetition ' + (L[1] + 1) + ' / ' + iv.count + ' \u00b7 interval ' + (L[0] + 1);
      rep.className = 'rep on';
    } else { rep.className = 'rep'; }
  }
  $('repetitions-body').addEventListener('click', function (e) {
    var t = e.target, tr = t.closest ? t.closest('tbody tr') : null;
    if (!tr || !P) return;
    var i = Array.prototype.indexOf.call(repRows, tr), iv = P.repetitions[i];
    if (!iv) return;
    var chip = t.closest('.iters span');
    if (chip) {
      var k = Array.prototype.indexOf.call(tr.querySelectorAll('.iters span'), chip);
      seek(iv.boundaries[Math.max(0, k)]);
    } else seek(iv.start);
  });

  // ---- trajectory plot over the whole recording ------------------------------
  var plot = $('plot'), pctx = plot ? plot.getContext('2d') : null;
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
  // The selected joint's trajectory samples (joint file), decoded once.
  var OV = {};
  function overview(k, j) {
    var key = k + '/' + j;
    if (OV[key]) return OV[key];
    var JF = REG['joint ' + key];
    if (!JF) return null;
    var o = JF.overview;
    OV[key] = { step: o.step, n: o.n, kp: unpack(o.kp, DIM, Q), conf: unpack(o.conf, 1, 0.01), prog: unpack(o.prog, DIM, Q) };
    return OV[key];
  }
  function drawPlotStatic() {
    if (!plot || !hasProgram()) return;
    var O = overview(PK, sel);
    if (!O) { PL = null; return; }
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
    var panels = [], R = P.repetitions, i, f, v, s;
    g.font = '11px system-ui, "DejaVu Sans", sans-serif';
    for (var k = 0; k < DIM; k++) {
      var py0 = top + k * (ph + gap), py1 = py0 + ph;
      var lo = Infinity, hi = -Infinity;
      for (i = 0; i < O.n; i++) {
        if (O.conf[i] > 0) { v = O.kp[i * DIM + k]; if (v < lo) lo = v; if (v > hi) hi = v; }
        v = O.prog[i * DIM + k]; if (v < lo) lo = v; if (v > hi) hi = v;
      }
      if (!isFinite(lo) || !isFinite(hi)) { lo = 0; hi = 1; }
      if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
      var padv = 0.08 * (hi - lo); lo -= padv; hi += padv;
      var inv = (D.units === 'px' && k === 1);
      var fy = (function (lo, hi, py0, py1, inv) {
        return function (v) { var a = (v - lo) / (hi - lo); return inv ? py0 + a * (py1 - py0) : py1 - a * (py1 - py0); };
      })(lo, hi, py0, py1, inv);
      panels.push({ py0: py0, py1: py1, fy: fy, k: k });
      g.fillStyle = '#f8fafc'; g.fillRect(x0, py0, x1 - x0, ph);
      g.strokeStyle = '#cbd5e1'; g.lineWidth = 1; g.strokeRect(x0 + .5, py0 + .5, x1 - x0 - 1, ph - 1);
      for (i = 0; i < R.length; i++) {
        var iv = R[i];
        g.fillStyle = 'rgba(20,184,166,.10)';
        g.fillRect(fx(iv.start), py0, Math.max(1, fx(iv.end - 1) - fx(iv.start)), ph);
        g.strokeStyle = 'rgba(15,118,110,.45)'; g.setLineDash([4, 3]);
        for (var bI = 0; bI < iv.boundaries.length; bI++) {
          var bx = fx(Math.min(iv.boundaries[bI], T - 1));
          if (bI > 0 && bx - fx(iv.boundaries[bI - 1]) < 3) continue;
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
      for (i = 0; i < O.n; i++) {
        var c = O.conf[i];
        if (c > 0) {
          g.fillStyle = 'rgba(71,85,105,' + (0.25 + 0.45 * Math.min(1, c)).toFixed(2) + ')';
          g.beginPath(); g.arc(fx(i * O.step), fy(O.kp[i * DIM + k]), 2.1, 0, 2 * Math.PI); g.fill();
        }
      }
      // The program: one stroke per run of samples in one segment.
      g.lineWidth = 2.4; g.lineJoin = 'round'; g.lineCap = 'round';
      i = 0;
      while (i < O.n) {
        s = segAt(i * O.step);
        var e = i + 1;
        while (e < O.n && segAt(e * O.step) === s) e++;
        g.strokeStyle = KC[kindOf(sel, s)]; g.fillStyle = g.strokeStyle;
        if (e - i === 1) {
          g.beginPath(); g.arc(fx(i * O.step), fy(O.prog[i * DIM + k]), 2.4, 0, 2 * Math.PI); g.fill();
        } else {
          g.beginPath();
          for (var q = i; q < e; q++) {
            var yy = fy(O.prog[q * DIM + k]);
            if (q === i) g.moveTo(fx(q * O.step), yy); else g.lineTo(fx(q * O.step), yy);
          }
          g.stroke();
        }
        i = e;
      }
    }
    g.fillStyle = '#64748b'; g.textAlign = 'center'; g.textBaseline = 'top';
    var xt = niceTicks(0, span, 10);
    var last = panels[panels.length - 1];
    for (var qq = 0; qq < xt.length; qq++) { g.fillText(fmt(xt[qq]), fx(xt[qq]), last.py1 + 5); }
    PL = { fx: fx, panels: panels, x0: x0, x1: x1, O: O };
    drawPlot();
  }
  function drawPlot() {
    if (!PL || !pctx) return;
    pctx.setTransform(1, 0, 0, 1, 0, 0);
    pctx.drawImage(plotStatic, 0, 0);
    pctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    var x = PL.fx(cur), A = at(PK, cur), O = PL.O;
    var oi = Math.min(O.n - 1, Math.round(cur / O.step));
    pctx.strokeStyle = '#0f172a'; pctx.lineWidth = 1.2;
    for (var i = 0; i < PL.panels.length; i++) {
      var Pn = PL.panels[i];
      pctx.beginPath(); pctx.moveTo(x, Pn.py0); pctx.lineTo(x, Pn.py1); pctx.stroke();
      var v = A ? A.C.prog[(A.i * J + sel) * DIM + Pn.k] : O.prog[oi * DIM + Pn.k];
      pctx.beginPath(); pctx.arc(x, Pn.fy(v), 4.5, 0, 2 * Math.PI);
      pctx.fillStyle = '#f43f90'; pctx.fill(); pctx.strokeStyle = '#fff'; pctx.lineWidth = 1.5; pctx.stroke();
      pctx.strokeStyle = '#0f172a'; pctx.lineWidth = 1.2;
    }
  }
  if (plot) {
    plot.addEventListener('click', function (e) {
      if (!PL) return;
      var r = plot.getBoundingClientRect();
      var x = e.clientX - r.left;
      seek(Math.round((x - PL.x0) / (PL.x1 - PL.x0) * (T - 1)));
    });
  }
  window.addEventListener('resize', function () { drawPlotStatic(); });

  // ---- controls -------------------------------------------------------------
  var scrub = $('scrub'), playBtn = $('play'), readout = $('readout'), badge = $('badge');
  function update() {
    var s = hasProgram() ? segAt(cur) : 0;
    drawStage();
    updateListing(s);
    updateTimeline();
    updateRepetitions();
    drawPlot();
    prefetch();
    scrub.max = String(T - 1);
    scrub.value = String(cur);
    updateStrip();
    var t = (cur + OFF) / D.fps;
    badge.textContent = 'frame ' + (cur + OFF) + ' / ' + (OFF + T - 1) + ' \u00b7 ' + t.toFixed(2) + ' s';
    if (hasProgram()) {
      readout.textContent = 'segment ' + (s + 1) + ' / ' + NS + ' (frames ' + framesLabel(B[s] + OFF, B[s + 1] + OFF) + ') \u00b7 ' +
        D.joints[sel] + ': ' + KN[kindOf(sel, s)];
    } else {
      readout.textContent = PIC.length ? 'picture of frame ' + PIC[Math.max(0, nearestPic(cur + OFF))] : '';
    }
    status.setAttribute('data-frame', String(cur + OFF));
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
  if ($('show-kp')) $('show-kp').addEventListener('change', function (e) { showKp = e.target.checked; drawStage(); });
  if ($('show-prog')) $('show-prog').addEventListener('change', function (e) { showProg = e.target.checked; drawStage(); });
  document.addEventListener('keydown', function (e) {
    if (e.target && (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT')) return;
    if (e.key === ' ') { e.preventDefault(); setPlaying(!playing); }
    else if (e.key === 'ArrowRight') { setPlaying(false); seek(cur + 1); }
    else if (e.key === 'ArrowLeft') { setPlaying(false); seek(cur - 1); }
    else if (e.key === 'Home') { seek(0); }
  });
  stage.addEventListener('click', function (e) {
    var A = at(PK, cur);
    if (DIM < 2 || !A) return;
    var r = stage.getBoundingClientRect();
    var x = (e.clientX - r.left) / r.width * stage.width, y = (e.clientY - r.top) / r.height * stage.height;
    var best = -1, bd = Infinity;
    for (var j = 0; j < J; j++) {
      if (A.C.conf[A.i * J + j] <= D.minConf) continue;
      var q = pt(A.C.kp, A.i, j), d = (q[0] - x) * (q[0] - x) + (q[1] - y) * (q[1] - y);
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
      (function (g) { g.addEventListener('click', function () { setPlaying(false); pickPerson(+g.getAttribute('data-person')); }); })(rows[ri]);
    }
  }
  function updateStrip() {
    if (!stripCursor) return;
    var x0 = +strip.getAttribute('data-x0'), x1 = +strip.getAttribute('data-x1');
    stripCursor.setAttribute('x', String(x0 + (cur + OFF) / PEOPLE[0].frames * (x1 - x0) - 1));
  }
  // Shows person k's analysis, once their structure file is there; `joint`
  // (optional) is the joint to select, `video` the video frame to show.
  function pickPerson(k, joint, video) {
    if (!PEOPLE[k]) return;
    if (video === undefined) video = cur + OFF;
    need('person', String(k), 'p' + k + '/person.js', function (S) {
      PERSON[k] = S;
      PK = k; P = S;
      T = PEOPLE[k].frames; OFF = PEOPLE[k].offset || 0;
      B = S.bounds || [0, T]; NS = B.length - 1;
      cur = clamp(video - OFF, 0, T - 1);
      var put = function (id, html) { var el = $(id); if (el) { el.innerHTML = html || ''; el.className = el.className.replace(/\bloading\b/, ''); } };
      put('repetitions-body', S.repetitionsHtml);
      put('timeline-body', S.timeline);
      put('abstract-body', S.abstractHtml);
      if ($('listing-header')) $('listing-header').textContent = S.header || '';
      repRows = $('repetitions-body').querySelectorAll('table.reps tbody tr');
      lastRep = '';
      setupTimeline();
      listed = ''; activeLi = null; lastSeg = -1; lastSel = -1; PL = null;
      if (listBox) listBox.innerHTML = '<div class="empty">loading…</div>';
      var pick = $('person');
      if (pick) pick.value = String(k);
      var srows = strip ? strip.querySelectorAll('g.row') : [];
      for (var i = 0; i < srows.length; i++) {
        srows[i].setAttribute('opacity', srows[i].getAttribute('data-person') === String(k) || !srows[i].hasAttribute('data-person') ? '1' : '0.75');
      }
      status.setAttribute('data-person', PEOPLE[k].id === null ? '' : String(PEOPLE[k].id));
      selectJoint(joint === undefined ? (S.defaultJoint || 0) : joint);
    });
  }
  if ($('person')) $('person').addEventListener('change', function (e) { setPlaying(false); pickPerson(+e.target.value); });

  // The page is ready once what it first shows has loaded.
  function finishLoading() {
    ready = true;
    drawStage();
    measureCanvas();
    status.setAttribute('data-ready', '1');
    status.setAttribute('data-ms', String(Math.round(window.performance ? performance.now() : 0)));
    if (errors === 0) status.textContent = 'ok';
  }

  // A link may pick the person, the frame and the joint:
  // report.html#person=2&frame=120&joint=right_wrist (the frame of the video)
  var hash = {};
  (window.location.hash || '').replace(/^#/, '').split('&').forEach(function (kv) {
    var i = kv.indexOf('=');
    if (i > 0) hash[decodeURIComponent(kv.slice(0, i))] = decodeURIComponent(kv.slice(i + 1));
  });
  var start = 0;
  if (MANY && hash.person) {
    for (var hp = 0; hp < PEOPLE.length; hp++) if (String(PEOPLE[hp].id) === hash.person) start = hp;
  }
  var startJoint = (hash.joint && D.joints.indexOf(hash.joint) >= 0) ? D.joints.indexOf(hash.joint) : undefined;
  var startFrame = (hash.frame && isFinite(+hash.frame)) ? Math.round(+hash.frame) : PEOPLE[start].offset;
  pending++;
  pickPerson(start, startJoint, startFrame);
  pending--;
  settle();
})();
