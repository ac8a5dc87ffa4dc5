// softrod 3-D view: plays the embedded run with WebGL 1 (no libraries).
// Data layout: see softrod-viz's html.rs. Coordinates on the GPU are relative
// to the data's origin (float32 keeps ~1e-7 of the scene's size).
(function () {
  'use strict';
  var D = JSON.parse(document.getElementById('softrod-data').textContent);
  var status = document.getElementById('softrod-status');
  var PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2', '#17becf', '#bcbd22', '#7f7f7f'];
  var CABLE_COLOR = '#222831';
  var BODY_COLOR = '#9aa3b5';
  var OBSTACLE_COLOR = '#b8976a';
  var PLANE_COLOR = '#bba67a';
  var RING = 20;
  var FOV = 40 * Math.PI / 180;

  // ---------- small vector / matrix helpers (column-major 4x4) ----------
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function add(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
  function scale(a, s) { return [a[0] * s, a[1] * s, a[2] * s]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function norm(a) { return Math.sqrt(dot(a, a)); }
  function unit(a) { var n = norm(a); return n > 0 ? scale(a, 1 / n) : [0, 0, 0]; }
  function mul(a, b) {
    var o = new Float32Array(16);
    for (var c = 0; c < 4; c++) {
      for (var r = 0; r < 4; r++) {
        var s = 0;
        for (var k = 0; k < 4; k++) { s += a[k * 4 + r] * b[c * 4 + k]; }
        o[c * 4 + r] = s;
      }
    }
    return o;
  }
  function perspective(fovy, aspect, near, far) {
    var f = 1 / Math.tan(fovy / 2), nf = 1 / (near - far);
    return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
  }
  function lookAt(eye, target, up) {
    var z = unit(sub(eye, target)), x = unit(cross(up, z)), y = cross(z, x);
    return new Float32Array([x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0,
      -dot(x, eye), -dot(y, eye), -dot(z, eye), 1]);
  }
  // Rotation matrix columns of a quaternion [w, x, y, z] (normalized here).
  function quatAxes(w, x, y, z) {
    var n = Math.sqrt(w * w + x * x + y * y + z * z) || 1;
    w /= n; x /= n; y /= n; z /= n;
    return [
      [1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)],
      [2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)],
      [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]
    ];
  }
  function hexRgb(h) { return [parseInt(h.substr(1, 2), 16) / 255, parseInt(h.substr(3, 2), 16) / 255, parseInt(h.substr(5, 2), 16) / 255]; }
  // The shortest decimal text of a grid value (no 0.30000000000000004).
  function fmt(v, step) {
    var d = Math.max(0, Math.ceil(-Math.log10(step) + 1e-9));
    var s = v.toFixed(Math.min(d, 9));
    return s === '-0' || /^-0\.0*$/.test(s) ? s.substring(1) : s;
  }
  function niceStep(span, target) {
    var raw = span / target, p = Math.pow(10, Math.floor(Math.log10(raw))), m = raw / p;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
  }
  function lengthText(v) {
    if (v >= 1) { return fmt(v, v) + ' m'; }
    if (v >= 0.01) { return fmt(v * 100, v * 100) + ' cm'; }
    if (v >= 0.001) { return fmt(v * 1000, v * 1000) + ' mm'; }
    return fmt(v * 1e6, v * 1e6) + ' µm';
  }

  // ---------- decode ----------
  var Q = D.quantum, QS = D.quatScale;
  var nFrames = D.times.length;
  var up = unit(D.up);
  // Horizontal basis e1, e2 with e1 × e2 = up; world x (or y) projected.
  var e1 = Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  e1 = unit(sub(e1, scale(up, dot(e1, up))));
  var e2 = cross(up, e1);
  function axisName(v) {
    var names = ['x', 'y', 'z'];
    for (var i = 0; i < 3; i++) {
      if (Math.abs(Math.abs(v[i]) - 1) < 1e-9) { return (v[i] < 0 ? '−' : '') + names[i]; }
    }
    return null;
  }

  var rods = D.rods.map(function (r, i) {
    return { name: r.name, color: PALETTE[i % PALETTE.length], s: r.s, radius: r.radius, frames: r.frames,
      traceT: r.trace.t, traceP: r.trace.p, n: r.s.length };
  });
  var cables = D.cables;
  var bodies = D.bodies;
  // Obstacles: a mesh in the world (less the origin) when fixed, in the
  // carrier's frame when carried; anchor = the mean of the vertices.
  var obstacles = (D.obstacles || []).map(function (o) {
    var nv = o.mesh.length / 6, c = [0, 0, 0], reach = 0;
    for (var i = 0; i < nv; i++) { c = add(c, [o.mesh[6 * i], o.mesh[6 * i + 1], o.mesh[6 * i + 2]]); }
    c = scale(c, 1 / Math.max(1, nv));
    for (var j = 0; j < nv; j++) { reach = Math.max(reach, norm([o.mesh[6 * j], o.mesh[6 * j + 1], o.mesh[6 * j + 2]])); }
    return { name: o.name, shape: o.shape, mesh: o.mesh, triangles: o.triangles, frames: o.frames, anchor: c, reach: reach,
      infinite: o.shape === 'plane' || o.shape === 'cylinder' };
  });

  // Bounding box of everything over all frames (relative coordinates), with
  // radii and body sizes.
  var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  function grow(x, y, z, pad) {
    lo[0] = Math.min(lo[0], x - pad); lo[1] = Math.min(lo[1], y - pad); lo[2] = Math.min(lo[2], z - pad);
    hi[0] = Math.max(hi[0], x + pad); hi[1] = Math.max(hi[1], y + pad); hi[2] = Math.max(hi[2], z + pad);
  }
  rods.forEach(function (r) {
    r.frames.forEach(function (f) {
      for (var i = 0; i < r.n; i++) { grow(f[7 * i] * Q, f[7 * i + 1] * Q, f[7 * i + 2] * Q, r.radius[i]); }
    });
  });
  cables.forEach(function (c) {
    c.frames.forEach(function (f) { for (var i = 0; i < f.length; i += 3) { grow(f[i] * Q, f[i + 1] * Q, f[i + 2] * Q, 0); } });
  });
  bodies.forEach(function (b) {
    var pad = b.shape === 'sphere' ? b.radius : 0.5 * Math.sqrt(b.size[0] * b.size[0] + b.size[1] * b.size[1] + b.size[2] * b.size[2]);
    b.frames.forEach(function (f) { grow(f[0] * Q, f[1] * Q, f[2] * Q, pad); });
  });
  // Finite obstacles count in the framing; planes and cylinders are cut to
  // the region around the rods and would only push the camera back.
  obstacles.forEach(function (o) {
    if (o.infinite) { return; }
    if (o.frames === null) {
      for (var i = 0; i < o.mesh.length; i += 6) { grow(o.mesh[i], o.mesh[i + 1], o.mesh[i + 2], 0); }
    } else {
      o.frames.forEach(function (f) { grow(f[0] * Q, f[1] * Q, f[2] * Q, o.reach); });
    }
  });
  var center = scale(add(lo, hi), 0.5);
  var sceneR = Math.max(0.5 * norm(sub(hi, lo)), 1e-9);

  // ---------- WebGL ----------
  var canvas = document.getElementById('gl');
  var overlay = document.getElementById('overlay');
  var ctx2d = overlay.getContext('2d');
  var gl = canvas.getContext('webgl', { antialias: true, preserveDrawingBuffer: true }) ||
    canvas.getContext('experimental-webgl', { antialias: true, preserveDrawingBuffer: true });
  if (!gl) {
    window.softrodReportError('WebGL is not available in this browser: the 3-D view cannot be drawn (try another browser, or enable hardware acceleration).');
    return;
  }
  var uintIndex = gl.getExtension('OES_element_index_uint');

  function shader(type, src) {
    var s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) { throw new Error('shader: ' + gl.getShaderInfoLog(s)); }
    return s;
  }
  function program(vs, fs, attribs) {
    var p = gl.createProgram();
    gl.attachShader(p, shader(gl.VERTEX_SHADER, vs));
    gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fs));
    attribs.forEach(function (a, i) { gl.bindAttribLocation(p, i, a); });
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) { throw new Error('program: ' + gl.getProgramInfoLog(p)); }
    var u = {}, n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (var i = 0; i < n; i++) { var name = gl.getActiveUniform(p, i).name; u[name] = gl.getUniformLocation(p, name); }
    return { p: p, u: u };
  }
  // Lit surfaces: a headlight (from the eye) plus a soft key light from
  // above; two-sided so open ends and caps never go black.
  var lit = program(
    'attribute vec3 aPos; attribute vec3 aNrm; uniform mat4 uMVP; uniform mat4 uModel; uniform mat4 uRot;' +
    'varying vec3 vN; varying vec3 vP;' +
    'void main(){ vec4 w = uModel * vec4(aPos,1.0); vP = w.xyz; vN = (uRot * vec4(aNrm,0.0)).xyz; gl_Position = uMVP * w; }',
    'precision highp float; varying vec3 vN; varying vec3 vP; uniform vec3 uColor; uniform vec3 uEye; uniform vec3 uUp; uniform float uAlpha;' +
    'void main(){ vec3 n = normalize(vN); vec3 v = normalize(uEye - vP); float d = dot(n, v); if (d < 0.0) { n = -n; d = -d; }' +
    ' float key = max(dot(n, uUp), 0.0); float spec = pow(max(d, 0.0), 40.0);' +
    ' vec3 c = uColor * (0.30 + 0.58 * d + 0.17 * key) + vec3(0.22) * spec; gl_FragColor = vec4(min(c, vec3(1.0)), uAlpha); }',
    ['aPos', 'aNrm']);
  var flat = program(
    'attribute vec3 aPos; uniform mat4 uMVP; void main(){ gl_Position = uMVP * vec4(aPos,1.0); }',
    'precision mediump float; uniform vec4 uColor; void main(){ gl_FragColor = uColor; }',
    ['aPos']);
  var IDENT = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);

  function dynBuffer(floats) {
    var b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, floats * 4, gl.DYNAMIC_DRAW);
    return b;
  }
  function staticBuffer(target, data) {
    var b = gl.createBuffer();
    gl.bindBuffer(target, b);
    gl.bufferData(target, data, gl.STATIC_DRAW);
    return b;
  }
  function indexArray(list, nVerts) {
    if (nVerts > 65535) {
      if (!uintIndex) { throw new Error('a rod has ' + nVerts + ' vertices and this browser lacks OES_element_index_uint'); }
      return new Uint32Array(list);
    }
    return new Uint16Array(list);
  }

  // Tube of each rod: RING vertices per sample plus a cap fan at each end.
  rods.forEach(function (r) {
    var n = r.n, nv = n * RING + 2 * (RING + 1);
    r.nv = nv;
    r.verts = new Float32Array(nv * 6);
    r.vbo = dynBuffer(nv * 6);
    var idx = [];
    for (var i = 0; i + 1 < n; i++) {
      for (var j = 0; j < RING; j++) {
        var a = i * RING + j, b = i * RING + (j + 1) % RING, c = a + RING, d = b + RING;
        idx.push(a, b, c, b, d, c);
      }
    }
    var c0 = n * RING, c1 = c0 + RING + 1;
    for (var k = 0; k < RING; k++) {
      idx.push(c0 + RING, c0 + (k + 1) % RING, c0 + k);
      idx.push(c1 + RING, c1 + k, c1 + (k + 1) % RING);
    }
    r.indexType = nv > 65535 ? gl.UNSIGNED_INT : gl.UNSIGNED_SHORT;
    r.ibo = staticBuffer(gl.ELEMENT_ARRAY_BUFFER, indexArray(idx, nv));
    r.nIdx = idx.length;
    r.line = new Float32Array(n * 3);
    r.lineVbo = dynBuffer(n * 3);
    r.axes = new Float32Array(n * 18);
    r.axesVbo = dynBuffer(n * 18);
    var m = r.traceT.length;
    var tr = new Float32Array(m * 3);
    for (var t = 0; t < m * 3; t++) { tr[t] = r.traceP[t] * Q; }
    r.traceVbo = staticBuffer(gl.ARRAY_BUFFER, tr);
    r.traceN = m;
    var maxR = 0;
    for (var q = 0; q < n; q++) { maxR = Math.max(maxR, r.radius[q]); }
    r.axisLen = Math.max(2.2 * maxR, 0.035 * sceneR);
    r.axisStride = Math.max(1, Math.ceil((n - 1) / 24));
    r.nAxes = Math.floor((n - 1) / r.axisStride) + 1;
  });
  cables.forEach(function (c) {
    var most = 0;
    c.frames.forEach(function (f) { most = Math.max(most, f.length); });
    c.vbo = dynBuffer(most);
    c.buf = new Float32Array(most);
  });

  // Unit meshes for bodies: a cube of edge 1 and a sphere of radius 1.
  function cubeMesh() {
    var v = [], idx = [];
    var faces = [[0, 1], [0, -1], [1, 1], [1, -1], [2, 1], [2, -1]];
    faces.forEach(function (f, fi) {
      var a = f[0], s = f[1], b = (a + 1) % 3, c = (a + 2) % 3;
      var corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]];
      corners.forEach(function (uv) {
        var p = [0, 0, 0], nn = [0, 0, 0];
        p[a] = 0.5 * s; p[b] = 0.5 * uv[0]; p[c] = 0.5 * uv[1] * s; nn[a] = s;
        v.push(p[0], p[1], p[2], nn[0], nn[1], nn[2]);
      });
      idx.push(4 * fi, 4 * fi + 1, 4 * fi + 2, 4 * fi, 4 * fi + 2, 4 * fi + 3);
    });
    return { vbo: staticBuffer(gl.ARRAY_BUFFER, new Float32Array(v)), ibo: staticBuffer(gl.ELEMENT_ARRAY_BUFFER, new Uint16Array(idx)), n: idx.length };
  }
  function sphereMesh(nu, nv) {
    var v = [], idx = [];
    for (var i = 0; i <= nv; i++) {
      var th = Math.PI * i / nv;
      for (var j = 0; j <= nu; j++) {
        var ph = 2 * Math.PI * j / nu, p = [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)];
        v.push(p[0], p[1], p[2], p[0], p[1], p[2]);
      }
    }
    for (var a = 0; a < nv; a++) {
      for (var b = 0; b < nu; b++) {
        var k = a * (nu + 1) + b;
        idx.push(k, k + nu + 1, k + 1, k + 1, k + nu + 1, k + nu + 2);
      }
    }
    return { vbo: staticBuffer(gl.ARRAY_BUFFER, new Float32Array(v)), ibo: staticBuffer(gl.ELEMENT_ARRAY_BUFFER, new Uint16Array(idx)), n: idx.length };
  }
  obstacles.forEach(function (o) {
    o.vbo = staticBuffer(gl.ARRAY_BUFFER, new Float32Array(o.mesh));
    o.ibo = staticBuffer(gl.ELEMENT_ARRAY_BUFFER, new Uint16Array(o.triangles));
    o.n = o.triangles.length;
  });
  var cube = bodies.length ? cubeMesh() : null;
  var sphere = bodies.length ? sphereMesh(32, 16) : null;

  // Grid on the plane normal to `up` under everything, lines on multiples of
  // a 1-2-5 step in world coordinates (so labels are round numbers).
  var grid = (function () {
    var corners = [];
    for (var c = 0; c < 8; c++) { corners.push([c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]]); }
    var O = D.origin;
    var a1 = Infinity, b1 = -Infinity, a2 = Infinity, b2 = -Infinity, h = Infinity;
    var o1 = dot(O, e1), o2 = dot(O, e2), oh = dot(O, up);
    corners.forEach(function (p) {
      a1 = Math.min(a1, dot(p, e1) + o1); b1 = Math.max(b1, dot(p, e1) + o1);
      a2 = Math.min(a2, dot(p, e2) + o2); b2 = Math.max(b2, dot(p, e2) + o2);
      h = Math.min(h, dot(p, up) + oh);
    });
    var span = Math.max(b1 - a1, b2 - a2, 1e-9);
    var step = niceStep(span, 8);
    var lo1 = Math.floor(a1 / step - 0.5) * step, hi1 = Math.ceil(b1 / step + 0.5) * step;
    var lo2 = Math.floor(a2 / step - 0.5) * step, hi2 = Math.ceil(b2 / step + 0.5) * step;
    var n1 = Math.round((hi1 - lo1) / step), n2 = Math.round((hi2 - lo2) / step);
    var hRel = h - oh - 0.02 * span;
    function P(u1, u2) { return add(add(scale(e1, u1 - o1), scale(e2, u2 - o2)), scale(up, hRel)); }
    var pts = [];
    for (var i = 0; i <= n1; i++) { var u = lo1 + i * step; pts.push(P(u, lo2), P(u, hi2)); }
    for (var k = 0; k <= n2; k++) { var w = lo2 + k * step; pts.push(P(lo1, w), P(hi1, w)); }
    var f = new Float32Array(pts.length * 3);
    pts.forEach(function (p, q) { f[3 * q] = p[0]; f[3 * q + 1] = p[1]; f[3 * q + 2] = p[2]; });
    // World axes at the origin (if it is near the motion), two steps long.
    var org = scale(O, -1), L = 1.5 * step;
    var ax = new Float32Array([org[0], org[1], org[2], org[0] + L, org[1], org[2],
      org[0], org[1], org[2], org[0], org[1] + L, org[2], org[0], org[1], org[2], org[0], org[1], org[2] + L]);
    var labels = [];
    var n1name = axisName(e1) || 'e₁', n2name = axisName(e2) || 'e₂';
    // Label in the unit that keeps the numbers short.
    var unitName = step >= 0.1 ? 'm' : step >= 1e-4 ? 'mm' : 'µm';
    var unitScale = unitName === 'm' ? 1 : unitName === 'mm' ? 1e3 : 1e6;
    function lab(v) { return fmt(v * unitScale, step * unitScale); }
    var every = Math.max(1, Math.ceil(Math.max(n1, n2) / 10));
    // Labels for both candidate edges of each direction; draw() shows the
    // pair on the edges nearer the eye.
    [[lo2, -1], [hi2, 1]].forEach(function (edge, side) {
      for (var i1 = every; i1 < n1; i1 += every) { labels.push({ p: P(lo1 + i1 * step, edge[0] + edge[1] * 0.4 * step), t: lab(lo1 + i1 * step), dir: 2, side: side }); }
      labels.push({ p: P(0.5 * (lo1 + hi1), edge[0] + edge[1] * 1.2 * step), t: n1name + ' [' + unitName + ']', bold: true, dir: 2, side: side });
    });
    [[lo1, -1], [hi1, 1]].forEach(function (edge, side) {
      for (var i2 = every; i2 < n2; i2 += every) { labels.push({ p: P(edge[0] + edge[1] * 0.4 * step, lo2 + i2 * step), t: lab(lo2 + i2 * step), dir: 1, side: side }); }
      labels.push({ p: P(edge[0] + edge[1] * 1.2 * step, 0.5 * (lo2 + hi2)), t: n2name + ' [' + unitName + ']', bold: true, dir: 1, side: side });
    });
    var gridCenter = P(0.5 * (lo1 + hi1), 0.5 * (lo2 + hi2));
    var nearOrigin = norm(sub(org, center)) < 3 * sceneR;
    return { vbo: staticBuffer(gl.ARRAY_BUFFER, f), n: pts.length, step: step, labels: labels, center: gridCenter,
      corners: [P(lo1, lo2), P(hi1, lo2), P(lo1, hi2), P(hi1, hi2)],
      axesVbo: staticBuffer(gl.ARRAY_BUFFER, ax), axisTips: [[org[0] + L * 1.12, org[1], org[2]], [org[0], org[1] + L * 1.12, org[2]], [org[0], org[1], org[2] + L * 1.12]],
      showAxes: nearOrigin };
  })();

  // ---------- camera ----------
  var cam = { az: 0, el: 0, dist: 1, target: center.slice() };
  function fit() {
    cam.moved = false;
    var ex = Math.abs(dot(sub(hi, lo), e1)), ey = Math.abs(dot(sub(hi, lo), e2));
    // Look across the plane of widest motion, turned 28° for depth.
    cam.az = (ex >= ey ? -90 + 28 : 180 - 28) * Math.PI / 180;
    cam.el = 16 * Math.PI / 180;
    cam.target = center.slice();
    // Smallest distance at which every corner of the bounding box is inside
    // the view: a corner at (x, y, z) in camera axes (z towards the eye) needs
    // dist ≥ z + |x| / tan(half-angle), and the same for y.
    var aspect = (canvas.clientWidth - legendWidth()) / Math.max(1, canvas.clientHeight);
    var ty = Math.tan(FOV / 2), tx = ty * Math.max(0.2, aspect);
    cam.dist = 1;
    var eye = eyePos(), zc = unit(sub(eye, cam.target)), xc = unit(cross(up, zc)), yc = cross(zc, xc);
    var need = 0, pts = grid.corners.slice();
    for (var c = 0; c < 8; c++) { pts.push([c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]]); }
    for (var k = 0; k < pts.length; k++) {
      var p = sub(pts[k], cam.target);
      var z = dot(p, zc);
      need = Math.max(need, z + Math.abs(dot(p, xc)) / tx, z + Math.abs(dot(p, yc)) / ty);
    }
    cam.dist = Math.max(1.06 * need, 1e-9);
  }
  // The legend covers the right of the canvas: the fitted view is centred
  // in the part left of it (an off-centre projection, see draw()).
  function legendWidth() {
    var L = document.getElementById('legend');
    var w = L.offsetWidth ? L.offsetWidth + 24 : 0;
    return w < 0.45 * canvas.clientWidth ? w : 0;
  }
  function eyePos() {
    var ce = Math.cos(cam.el);
    var dir = add(add(scale(e1, ce * Math.cos(cam.az)), scale(e2, ce * Math.sin(cam.az))), scale(up, Math.sin(cam.el)));
    return add(cam.target, scale(dir, cam.dist));
  }

  // ---------- state and UI ----------
  var frame = 0, playing = false, simTime = D.times[0], lastWall = null;
  var slider = document.getElementById('slider'), playBtn = document.getElementById('play');
  var timeEl = document.getElementById('time'), speedSel = document.getElementById('speed');
  var cbLoop = document.getElementById('loop'), cbTrace = document.getElementById('trace');
  var cbAxes = document.getElementById('axes'), cbGrid = document.getElementById('grid');
  slider.max = String(nFrames - 1);
  cbAxes.checked = !!D.options.axes;
  var t0 = D.times[0], t1 = D.times[nFrames - 1], duration = t1 - t0;
  var SPEEDS = [1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 0.01, 0.02, 0.05, 0.1, 0.2, 0.25, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000];
  var want = D.options.speed || (duration > 0 ? duration / 10 : 1);
  var best = 0;
  SPEEDS.forEach(function (s, i) { if (Math.abs(Math.log(s / want)) < Math.abs(Math.log(SPEEDS[best] / want))) { best = i; } });
  if (D.options.speed && Math.abs(SPEEDS[best] / want - 1) > 1e-9) { SPEEDS.splice(best + (SPEEDS[best] < want ? 1 : 0), 0, want); best = SPEEDS.indexOf(want); }
  SPEEDS.forEach(function (s, i) {
    var o = document.createElement('option');
    o.value = String(s);
    o.textContent = '×' + String(s);
    if (s === 1) { o.title = 'real time'; }
    if (i === best) { o.selected = true; }
    speedSel.appendChild(o);
  });
  var dtMin = Infinity;
  for (var i = 1; i < nFrames; i++) { if (D.times[i] > D.times[i - 1]) { dtMin = Math.min(dtMin, D.times[i] - D.times[i - 1]); } }
  var decimals = isFinite(dtMin) ? Math.min(7, Math.max(2, Math.ceil(-Math.log10(dtMin) + 0.3))) : 3;
  var width = Math.max(String(nFrames).length, 1);

  (function info() {
    var lines = [];
    var kept = nFrames === D.sourceFrames ? nFrames + ' frames (all output times)'
      : nFrames + ' of ' + D.sourceFrames + ' output frames shown (about one in ' + ((D.sourceFrames - 1) / (nFrames - 1 || 1)).toFixed(1) + '; first and last kept)';
    lines.push(kept);
    lines.push('budget: ≤ ' + D.budget.maxFrames + ' frames, ≤ ' + (D.budget.maxBytes / 1e6).toFixed(0) + ' MB per page');
    lines.push('grid squares: ' + lengthText(grid.step) + ' · tubes drawn at the rods\' radii');
    document.getElementById('info').textContent = lines.join('\n');
  })();
  (function legend() {
    var L = document.getElementById('legend');
    function head(t) { var d = document.createElement('div'); d.className = 'hd'; d.textContent = t; L.appendChild(d); }
    function row(color, text, line) {
      var d = document.createElement('div'); d.className = 'row';
      var s = document.createElement('span'); s.className = 'sw' + (line ? ' line' : ''); s.style.background = color;
      var t = document.createElement('span'); t.textContent = text;
      d.appendChild(s); d.appendChild(t); L.appendChild(d);
    }
    if (rods.length) {
      head(rods.length === 1 ? 'rod' : 'rods');
      rods.forEach(function (r) {
        var rmax = Math.max.apply(null, r.radius), rmin = Math.min.apply(null, r.radius);
        var rt = rmax === rmin ? 'r = ' + lengthText(rmax) : 'r = ' + lengthText(rmax) + ' → ' + lengthText(r.radius[r.n - 1]);
        row(r.color, r.name + '  (' + rt + ')');
      });
    }
    if (cables.length) { head('cables'); cables.forEach(function (c) { row(CABLE_COLOR, c.name, true); }); }
    if (bodies.length) { head('bodies'); bodies.forEach(function (b) { row(BODY_COLOR, b.name); }); }
    if (obstacles.length) {
      head('obstacles');
      obstacles.forEach(function (o) { row(o.shape === 'plane' ? PLANE_COLOR : OBSTACLE_COLOR, o.name + ' (' + o.shape + (o.frames === null ? '' : ', carried') + ')'); });
    }
    head('axes');
    row('#d62728', 'x', true); row('#2ca02c', 'y', true); row('#1f4fd6', 'z', true);
  })();

  function setFrame(k) {
    frame = Math.max(0, Math.min(nFrames - 1, k | 0));
    simTime = D.times[frame];
    slider.value = String(frame);
    draw();
  }
  function setPlaying(p) {
    playing = p && nFrames > 1;
    playBtn.innerHTML = playing ? '&#10074;&#10074;' : '&#9654;';
    lastWall = null;
    if (playing) {
      if (frame >= nFrames - 1) { setFrame(0); }
      requestAnimationFrame(tick);
    }
  }
  function tick(now) {
    if (!playing) { return; }
    if (lastWall !== null) {
      simTime += (now - lastWall) / 1000 * Number(speedSel.value);
      if (simTime > t1) {
        if (cbLoop.checked) { simTime = t0 + (duration > 0 ? (simTime - t0) % duration : 0); } else { simTime = t1; playing = false; setPlaying(false); }
      }
      var k = frame;
      if (D.times[k] > simTime) { k = 0; }
      while (k + 1 < nFrames && D.times[k + 1] <= simTime) { k++; }
      if (k !== frame) { frame = k; slider.value = String(k); draw(); }
    }
    lastWall = now;
    if (playing) { requestAnimationFrame(tick); }
  }
  playBtn.addEventListener('click', function () { setPlaying(!playing); });
  slider.addEventListener('input', function () { setPlaying(false); setFrame(Number(slider.value)); });
  [cbTrace, cbAxes, cbGrid].forEach(function (c) { c.addEventListener('change', draw); });
  document.getElementById('fit').addEventListener('click', function () { fit(); draw(); });
  window.addEventListener('keydown', function (e) {
    if (e.target && e.target.tagName === 'SELECT') { return; }
    if (e.key === ' ') { setPlaying(!playing); e.preventDefault(); }
    else if (e.key === 'ArrowRight') { setPlaying(false); setFrame(frame + 1); e.preventDefault(); }
    else if (e.key === 'ArrowLeft') { setPlaying(false); setFrame(frame - 1); e.preventDefault(); }
  });

  // Mouse: orbit, pan, zoom.
  var drag = null;
  canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
  canvas.addEventListener('mousedown', function (e) { drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey }; });
  window.addEventListener('mouseup', function () { drag = null; });
  window.addEventListener('mousemove', function (e) {
    if (!drag) { return; }
    var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    cam.moved = true;
    if (drag.pan) {
      var eye = eyePos(), fwd = unit(sub(cam.target, eye)), right = unit(cross(fwd, up)), u2 = cross(right, fwd);
      var per = 2 * cam.dist * Math.tan(FOV / 2) / Math.max(1, canvas.clientHeight);
      cam.target = add(cam.target, add(scale(right, -dx * per), scale(u2, dy * per)));
    } else {
      cam.az -= dx * 0.008;
      cam.el = Math.max(-1.55, Math.min(1.55, cam.el + dy * 0.008));
    }
    draw();
  });
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    cam.moved = true;
    cam.dist *= Math.exp(Math.max(-0.5, Math.min(0.5, e.deltaY * 0.0015)));
    cam.dist = Math.max(sceneR * 1e-3, Math.min(sceneR * 1e3, cam.dist));
    draw();
  }, { passive: false });
  canvas.addEventListener('dblclick', function () { fit(); draw(); });
  // Until the user moves the camera, a resize refits the view (a window
  // that opens small and grows shows the same framing as one opened large).
  window.addEventListener('resize', function () { resize(); if (!cam.moved) { fit(); } draw(); });
  function resize() {
    // The stage ends above the control bar, so the fitted view is not hidden under it.
    var stage = document.getElementById('stage');
    var below = document.getElementById('controls').offsetHeight + document.getElementById('help').offsetHeight;
    if (stage.style.bottom !== below + 'px') { stage.style.bottom = below + 'px'; }
    var dpr = window.devicePixelRatio || 1;
    var w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    if (overlay.width !== w || overlay.height !== h) { overlay.width = w; overlay.height = h; }
  }

  // ---------- per-frame geometry ----------
  function updateRod(r, f) {
    var v = r.verts, n = r.n, R = r.radius, s = r.s;
    var ends = [];
    for (var i = 0; i < n; i++) {
      var b = 7 * i, px = f[b] * Q, py = f[b + 1] * Q, pz = f[b + 2] * Q;
      var A = quatAxes(f[b + 3] / QS, f[b + 4] / QS, f[b + 5] / QS, f[b + 6] / QS);
      var X = A[0], Y = A[1], Z = A[2];
      // Slope of the taper tilts the surface normal towards the tip.
      var ia = Math.max(0, i - 1), ib = Math.min(n - 1, i + 1);
      var slope = (R[ib] - R[ia]) / (s[ib] - s[ia]);
      for (var j = 0; j < RING; j++) {
        var th = 2 * Math.PI * j / RING, c = Math.cos(th), sn = Math.sin(th);
        var dx = c * Y[0] + sn * Z[0], dy = c * Y[1] + sn * Z[1], dz = c * Y[2] + sn * Z[2];
        var o = 6 * (i * RING + j);
        v[o] = px + R[i] * dx; v[o + 1] = py + R[i] * dy; v[o + 2] = pz + R[i] * dz;
        v[o + 3] = dx - slope * X[0]; v[o + 4] = dy - slope * X[1]; v[o + 5] = dz - slope * X[2];
      }
      r.line[3 * i] = px; r.line[3 * i + 1] = py; r.line[3 * i + 2] = pz;
      // Axes buffer: all x axes, then all y, then all z (one draw each);
      // at most ~24 samples per rod get axes, so they stay readable.
      var L = r.axisLen, ax = r.axes, slot = i / r.axisStride;
      if (i % r.axisStride === 0) [X, Y, Z].forEach(function (E, e) {
        var q = 6 * (e * r.nAxes + slot);
        ax[q] = px; ax[q + 1] = py; ax[q + 2] = pz;
        ax[q + 3] = px + L * E[0]; ax[q + 4] = py + L * E[1]; ax[q + 5] = pz + L * E[2];
      });
      if (i === 0 || i === n - 1) { ends.push({ i: i, X: X, p: [px, py, pz] }); }
    }
    ends.forEach(function (e, k) {
      var o0 = 6 * (n * RING + k * (RING + 1)), sg = k === 0 ? -1 : 1;
      for (var j = 0; j < RING; j++) {
        var src = 6 * (e.i * RING + j), o = o0 + 6 * j;
        v[o] = v[src]; v[o + 1] = v[src + 1]; v[o + 2] = v[src + 2];
        v[o + 3] = sg * e.X[0]; v[o + 4] = sg * e.X[1]; v[o + 5] = sg * e.X[2];
      }
      var oc = o0 + 6 * RING;
      v[oc] = e.p[0]; v[oc + 1] = e.p[1]; v[oc + 2] = e.p[2];
      v[oc + 3] = sg * e.X[0]; v[oc + 4] = sg * e.X[1]; v[oc + 5] = sg * e.X[2];
    });
    r.tip = [f[7 * (n - 1)] * Q, f[7 * (n - 1) + 1] * Q, f[7 * (n - 1) + 2] * Q];
    gl.bindBuffer(gl.ARRAY_BUFFER, r.vbo); gl.bufferSubData(gl.ARRAY_BUFFER, 0, v);
    gl.bindBuffer(gl.ARRAY_BUFFER, r.lineVbo); gl.bufferSubData(gl.ARRAY_BUFFER, 0, r.line);
    gl.bindBuffer(gl.ARRAY_BUFFER, r.axesVbo); gl.bufferSubData(gl.ARRAY_BUFFER, 0, r.axes);
  }

  function project(mvp, p) {
    var x = mvp[0] * p[0] + mvp[4] * p[1] + mvp[8] * p[2] + mvp[12];
    var y = mvp[1] * p[0] + mvp[5] * p[1] + mvp[9] * p[2] + mvp[13];
    var w = mvp[3] * p[0] + mvp[7] * p[1] + mvp[11] * p[2] + mvp[15];
    if (w <= 0) { return null; }
    return [(x / w * 0.5 + 0.5) * overlay.width, (0.5 - y / w * 0.5) * overlay.height];
  }

  function drawLines(vbo, count, mode, mvp, rgba) {
    gl.useProgram(flat.p);
    gl.uniformMatrix4fv(flat.u.uMVP, false, mvp);
    gl.uniform4fv(flat.u.uColor, rgba);
    gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
    gl.enableVertexAttribArray(0);
    gl.disableVertexAttribArray(1);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 12, 0);
    gl.drawArrays(mode, 0, count);
  }
  function drawMesh(vbo, ibo, count, type, mvp, model, rot, rgb, eye, alpha) {
    gl.useProgram(lit.p);
    gl.uniformMatrix4fv(lit.u.uMVP, false, mvp);
    gl.uniformMatrix4fv(lit.u.uModel, false, model);
    gl.uniformMatrix4fv(lit.u.uRot, false, rot);
    gl.uniform3fv(lit.u.uColor, rgb);
    gl.uniform3fv(lit.u.uEye, eye);
    gl.uniform3fv(lit.u.uUp, up);
    gl.uniform1f(lit.u.uAlpha, alpha === undefined ? 1.0 : alpha);
    gl.bindBuffer(gl.ARRAY_BUFFER, vbo);
    gl.enableVertexAttribArray(0);
    gl.enableVertexAttribArray(1);
    gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 24, 0);
    gl.vertexAttribPointer(1, 3, gl.FLOAT, false, 24, 12);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, ibo);
    gl.drawElements(gl.TRIANGLES, count, type, 0);
  }
  function bodyMatrices(b, f) {
    var A = quatAxes(f[3] / QS, f[4] / QS, f[5] / QS, f[6] / QS);
    var sz = b.shape === 'sphere' ? [b.radius, b.radius, b.radius] : b.size;
    var m = new Float32Array(16), r = new Float32Array(16);
    for (var c = 0; c < 3; c++) {
      for (var k = 0; k < 3; k++) { m[4 * c + k] = A[c][k] * sz[c]; r[4 * c + k] = A[c][k]; }
    }
    m[12] = f[0] * Q; m[13] = f[1] * Q; m[14] = f[2] * Q; m[15] = 1; r[15] = 1;
    return [m, r];
  }

  // Model and normal matrices of an obstacle at the kept frame k (identity
  // when fixed: its mesh is already relative to the origin).
  function obstacleMatrices(o, k) {
    if (o.frames === null) { return [IDENT, IDENT]; }
    var f = o.frames[k], A = quatAxes(f[3] / QS, f[4] / QS, f[5] / QS, f[6] / QS);
    var m = new Float32Array(16), r = new Float32Array(16);
    for (var c = 0; c < 3; c++) {
      for (var j = 0; j < 3; j++) { m[4 * c + j] = A[c][j]; r[4 * c + j] = A[c][j]; }
    }
    m[12] = f[0] * Q; m[13] = f[1] * Q; m[14] = f[2] * Q; m[15] = 1; r[15] = 1;
    return [m, r];
  }
  function obstacleAnchor(o, k) {
    if (o.frames === null) { return o.anchor; }
    var f = o.frames[k], A = quatAxes(f[3] / QS, f[4] / QS, f[5] / QS, f[6] / QS), a = o.anchor;
    return [f[0] * Q + A[0][0] * a[0] + A[1][0] * a[1] + A[2][0] * a[2],
      f[1] * Q + A[0][1] * a[0] + A[1][1] * a[1] + A[2][1] * a[2],
      f[2] * Q + A[0][2] * a[0] + A[1][2] * a[1] + A[2][2] * a[2]];
  }

  function draw() {
    resize();
    var W = canvas.width, H = canvas.height;
    gl.viewport(0, 0, W, H);
    gl.clearColor(0.957, 0.961, 0.969, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA);
    var eye = eyePos();
    var near = Math.max(cam.dist * 1e-3, cam.dist - 4 * sceneR), far = cam.dist + 4 * sceneR;
    near = Math.min(near, cam.dist * 0.1);
    var shift = new Float32Array(IDENT);
    shift[12] = -legendWidth() / Math.max(1, canvas.clientWidth);
    var mvp = mul(mul(shift, perspective(FOV, W / H, near, far)), lookAt(eye, cam.target, up));
    var t = D.times[frame];

    if (cbGrid.checked) {
      drawLines(grid.vbo, grid.n, gl.LINES, mvp, [0.62, 0.65, 0.71, 0.9]);
    }
    if (grid.showAxes) {
      var axc = [[0.84, 0.15, 0.16, 1], [0.17, 0.63, 0.17, 1], [0.12, 0.31, 0.84, 1]];
      gl.useProgram(flat.p);
      for (var a = 0; a < 3; a++) {
        gl.bindBuffer(gl.ARRAY_BUFFER, grid.axesVbo);
        gl.uniformMatrix4fv(flat.u.uMVP, false, mvp);
        gl.uniform4fv(flat.u.uColor, axc[a]);
        gl.enableVertexAttribArray(0); gl.disableVertexAttribArray(1);
        gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 12, 0);
        gl.drawArrays(gl.LINES, 2 * a, 2);
      }
    }
    var pxPerM = H / (2 * cam.dist * Math.tan(FOV / 2));
    rods.forEach(function (r) {
      updateRod(r, r.frames[frame]);
      var rgb = hexRgb(r.color);
      drawMesh(r.vbo, r.ibo, r.nIdx, r.indexType, mvp, IDENT, IDENT, rgb, eye);
      // A tube thinner than ~1.5 px would vanish: draw its centreline too.
      var rmax = Math.max.apply(null, r.radius);
      if (rmax * pxPerM < 1.5) { drawLines(r.lineVbo, r.n, gl.LINE_STRIP, mvp, rgb.concat([1])); }
      if (cbAxes.checked) {
        var cols = [[0.84, 0.15, 0.16, 1], [0.17, 0.63, 0.17, 1], [0.12, 0.31, 0.84, 1]];
        for (var e = 0; e < 3; e++) {
          gl.useProgram(flat.p);
          gl.uniformMatrix4fv(flat.u.uMVP, false, mvp);
          gl.uniform4fv(flat.u.uColor, cols[e]);
          gl.bindBuffer(gl.ARRAY_BUFFER, r.axesVbo);
          gl.enableVertexAttribArray(0); gl.disableVertexAttribArray(1);
          gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 12, 0);
          gl.drawArrays(gl.LINES, 2 * r.nAxes * e, 2 * r.nAxes);
        }
      }
      if (cbTrace.checked && r.traceN > 1) {
        var upto = 0;
        while (upto < r.traceN && r.traceT[upto] <= t) { upto++; }
        gl.depthMask(false);
        drawLines(r.traceVbo, r.traceN, gl.LINE_STRIP, mvp, rgb.map(function (c) { return 0.5 * c + 0.3; }).concat([0.7]));
        if (upto > 1) { drawLines(r.traceVbo, upto, gl.LINE_STRIP, mvp, rgb.map(function (c) { return 0.75 * c; }).concat([1])); }
        gl.depthMask(true);
      }
    });
    cables.forEach(function (c) {
      var f = c.frames[frame];
      for (var i = 0; i < f.length; i++) { c.buf[i] = f[i] * Q; }
      gl.bindBuffer(gl.ARRAY_BUFFER, c.vbo); gl.bufferSubData(gl.ARRAY_BUFFER, 0, c.buf.subarray(0, f.length));
      gl.disable(gl.DEPTH_TEST);
      drawLines(c.vbo, f.length / 3, gl.LINE_STRIP, mvp, hexRgb(CABLE_COLOR).concat([1]));
      gl.enable(gl.DEPTH_TEST);
    });
    bodies.forEach(function (b) {
      var M = bodyMatrices(b, b.frames[frame]), mesh = b.shape === 'sphere' ? sphere : cube;
      drawMesh(mesh.vbo, mesh.ibo, mesh.n, gl.UNSIGNED_SHORT, mvp, M[0], M[1], hexRgb(BODY_COLOR), eye);
    });
    // Solid obstacles, then planes see-through (a rod under a table shows).
    obstacles.forEach(function (o) {
      if (o.shape === 'plane') { return; }
      var M = obstacleMatrices(o, frame);
      drawMesh(o.vbo, o.ibo, o.n, gl.UNSIGNED_SHORT, mvp, M[0], M[1], hexRgb(OBSTACLE_COLOR), eye);
    });
    gl.depthMask(false);
    obstacles.forEach(function (o) {
      if (o.shape !== 'plane') { return; }
      var M = obstacleMatrices(o, frame);
      drawMesh(o.vbo, o.ibo, o.n, gl.UNSIGNED_SHORT, mvp, M[0], M[1], hexRgb(PLANE_COLOR), eye, 0.55);
    });
    gl.depthMask(true);

    // Text: grid numbers, axis names, rod names at the tips.
    ctx2d.clearRect(0, 0, overlay.width, overlay.height);
    var dpr = window.devicePixelRatio || 1;
    ctx2d.textAlign = 'center';
    ctx2d.textBaseline = 'middle';
    if (cbGrid.checked) {
      var toEye = sub(eye, grid.center);
      var near1 = dot(toEye, e1) > 0 ? 1 : 0, near2 = dot(toEye, e2) > 0 ? 1 : 0;
      grid.labels.forEach(function (l) {
        if (l.side !== (l.dir === 2 ? near2 : near1)) { return; }
        var p = project(mvp, l.p);
        if (!p) { return; }
        ctx2d.font = (l.bold ? '600 ' : '') + Math.round(12.5 * dpr) + 'px system-ui, "DejaVu Sans", sans-serif';
        ctx2d.fillStyle = l.bold ? '#2c3344' : '#5b6477';
        ctx2d.fillText(l.t, p[0], p[1]);
      });
    }
    if (grid.showAxes) {
      ctx2d.font = '600 ' + Math.round(13 * dpr) + 'px system-ui, "DejaVu Sans", sans-serif';
      ['x', 'y', 'z'].forEach(function (nm, a) {
        var p = project(mvp, grid.axisTips[a]);
        if (p) { ctx2d.fillStyle = ['#b21f20', '#1f7a1f', '#1f3fb0'][a]; ctx2d.fillText(nm, p[0], p[1]); }
      });
    }
    if (rods.length > 1) {
      ctx2d.font = Math.round(12.5 * dpr) + 'px system-ui, "DejaVu Sans", sans-serif';
      ctx2d.textAlign = 'left';
      rods.forEach(function (r) {
        var p = project(mvp, r.tip);
        if (p) { ctx2d.fillStyle = r.color; ctx2d.fillText(r.name, p[0] + 8 * dpr, p[1] - 8 * dpr); }
      });
    }

    var tt = t.toFixed(decimals);
    timeEl.textContent = 't = ' + tt + ' s / ' + t1.toFixed(decimals) + ' s  frame ' + String(frame).padStart(width, ' ') + '/' + (nFrames - 1);
    // Where each rod's tip is on screen (CSS pixels): lets a test compare
    // the drawn picture with the data.
    status.setAttribute('data-tips', rods.map(function (r) {
      var p = project(mvp, r.tip);
      return p ? (p[0] / dpr).toFixed(1) + ',' + (p[1] / dpr).toFixed(1) : 'behind';
    }).join(';'));
    status.setAttribute('data-obstacles', obstacles.map(function (o) {
      var p = project(mvp, obstacleAnchor(o, frame));
      return p ? (p[0] / dpr).toFixed(1) + ',' + (p[1] / dpr).toFixed(1) : 'behind';
    }).join(';'));
    status.setAttribute('data-viewport', window.innerWidth + 'x' + window.innerHeight);
    status.setAttribute('data-frame', String(frame));
    status.setAttribute('data-ready', '1');
  }

  // ---------- start ----------
  function hashFrame() {
    var m = /(?:^#|&)frame=(last|\d+)/.exec(location.hash);
    if (!m) { return null; }
    return m[1] === 'last' ? nFrames - 1 : Number(m[1]);
  }
  window.addEventListener('hashchange', function () { var k = hashFrame(); if (k !== null) { setPlaying(false); setFrame(k); } });
  // Hash options (for links and tests): frame=N|last, trace=0, grid=0, axes=1.
  if (/(?:^#|&)trace=0/.test(location.hash)) { cbTrace.checked = false; }
  if (/(?:^#|&)grid=0/.test(location.hash)) { cbGrid.checked = false; }
  if (/(?:^#|&)axes=1/.test(location.hash)) { cbAxes.checked = true; }
  resize();
  fit();
  var start = hashFrame();
  setFrame(start === null ? 0 : start);
  if (start === null && nFrames > 1) { setPlaying(true); }
  window.softrodView = { setFrame: setFrame, frames: nFrames, play: function () { setPlaying(true); }, pause: function () { setPlaying(false); } };
})();
