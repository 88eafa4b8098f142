// Gradus comparison viewer: written by `imgtool compare` beside data.js (the
// images' metadata and metrics) and img-K.js (each image's linear RGB as
// deflated half floats). Tone mapping runs in a WebGL2 fragment shader.
'use strict';
(function () {
  const D = window.GRADUS_COMPARE;
  if (!D) {
    document.getElementById('status').textContent = 'data.js is missing beside index.html';
    return;
  }
  const W = D.width, H = D.height, N = D.images.length;
  const MODES = ['sRGB', 'false colour', 'relative error'];
  // Ramp of imgtool falsecolor (display values): black, purple, red, orange, yellow, white.
  const RAMP = [[0, 0, 0], [0.35, 0.05, 0.55], [0.85, 0.1, 0.25], [1, 0.55, 0], [1, 0.95, 0.1], [1, 1, 1]];
  const FALSE_LO = -10, FALSE_HI = 2;  // log2 luminance range of the false-colour view
  const CROP_COLOURS = ['#ffd900', '#00e5ff', '#ff4de6', '#66ff4d', '#ff8c1a', '#b3b3ff'];

  const $ = (id) => document.getElementById(id);
  const viewer = $('viewer'), glCanvas = $('gl'), overlay = $('overlay'), status = $('status');
  const state = {
    current: N > 1 ? 1 : 0, mode: 0, exposure: D.exposure, errLog: Math.log10(D.error_max),
    grid: false, cropMode: false, zoom: 1, cx: W / 2, cy: H / 2, crops: [], ready: false,
  };
  const pixels = [];  // per image: interleaved RGB half bits (Uint16Array)
  let gl = null, prog = null, textures = [], uni = {}, panels = [], drawQueued = false;

  function fail(msg) {
    status.textContent = msg;
    status.classList.add('error');
    throw new Error(msg);
  }

  // ---------- numbers ----------
  function halfToFloat(h) {
    const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 31, f = h & 1023;
    if (e === 0) return s * f * Math.pow(2, -24);
    if (e === 31) return f ? NaN : s * Infinity;
    return s * (1 + f / 1024) * Math.pow(2, e - 15);
  }
  function fmt(v, digits) {
    if (v === null || v === undefined) return '\u2013';
    if (typeof v !== 'number') return String(v);
    if (!isFinite(v)) return String(v);
    return Number(v.toPrecision(digits || 4)).toString();
  }
  function esc(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
  }

  // ---------- data loading ----------
  function loadScript(src) {
    return new Promise((resolve, reject) => {
      const s = document.createElement('script');
      s.src = src;
      s.onload = resolve;
      s.onerror = () => reject(new Error('cannot load ' + src + ' (is it beside index.html?)'));
      document.body.appendChild(s);
    });
  }
  async function decodeImage(k) {
    await loadScript(D.images[k].data);
    const b64 = window.GRADUS_IMAGES[k];
    delete window.GRADUS_IMAGES[k];
    const bin = atob(b64);
    const packed = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) packed[i] = bin.charCodeAt(i);
    const stream = new Blob([packed]).stream().pipeThrough(new DecompressionStream('deflate'));
    const raw = new Uint8Array(await new Response(stream).arrayBuffer());
    const npix = W * H, n = npix * 3;
    if (raw.length !== 2 * n) throw new Error(D.images[k].data + ': ' + raw.length + ' bytes, expected ' + 2 * n);
    // Planes R, G, B of low bytes, then of high bytes -> interleaved RGB.
    const out = new Uint16Array(n);
    for (let c = 0; c < 3; ++c) {
      for (let i = 0, k2 = c * npix; i < npix; ++i, ++k2) out[i * 3 + c] = raw[k2] | (raw[n + k2] << 8);
    }
    return out;
  }

  // ---------- WebGL ----------
  const VS = `#version 300 es
  in vec2 a_pos;
  void main() { gl_Position = vec4(a_pos, 0.0, 1.0); }`;
  const FS = `#version 300 es
  precision highp float; precision highp int; precision highp sampler2D;
  uniform sampler2D u_img, u_ref;
  uniform vec4 u_panel;   // lower-left x, y in the framebuffer, width, height
  uniform vec3 u_view;    // zoom (framebuffer pixels per image pixel), image point at the panel centre
  uniform ivec2 u_size;
  uniform float u_scale;  // 2^exposure
  uniform int u_mode;     // 0 sRGB, 1 false colour, 2 relative error
  uniform float u_errMax, u_eps;
  out vec4 o;
  const vec3 R0 = vec3(0.0), R1 = vec3(0.35, 0.05, 0.55), R2 = vec3(0.85, 0.1, 0.25),
             R3 = vec3(1.0, 0.55, 0.0), R4 = vec3(1.0, 0.95, 0.1), R5 = vec3(1.0);
  vec3 ramp(float t) {
    float x = clamp(t, 0.0, 1.0) * 5.0;
    int k = min(int(x), 4);
    float f = x - float(k);
    if (k == 0) return mix(R0, R1, f);
    if (k == 1) return mix(R1, R2, f);
    if (k == 2) return mix(R2, R3, f);
    if (k == 3) return mix(R3, R4, f);
    return mix(R4, R5, f);
  }
  // imgtool's PNG encoding: clamp to [0,1], IEC 61966-2-1, rounded to 8 bits.
  float srgb8(float v) {
    if (v <= 0.0) return 0.0;
    if (v >= 1.0) return 1.0;
    float s = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return floor(s * 255.0 + 0.5) / 255.0;
  }
  bool bad(vec3 v) { return any(isnan(v)) || any(isinf(v)); }
  void main() {
    vec2 f = gl_FragCoord.xy - u_panel.xy;
    vec2 s = vec2(f.x - 0.5 * u_panel.z, 0.5 * u_panel.w - f.y);
    ivec2 ip = ivec2(floor(s / u_view.x + u_view.yz));
    if (any(lessThan(ip, ivec2(0))) || any(greaterThanEqual(ip, u_size))) {
      o = vec4(0.2, 0.2, 0.2, 1.0);
      return;
    }
    vec3 v = texelFetch(u_img, ip, 0).rgb;
    vec3 c;
    if (u_mode == 2) {
      vec3 r = texelFetch(u_ref, ip, 0).rgb;
      vec3 e = (v - r) * (v - r) / (r * r + u_eps);
      c = bad(v) || bad(r) ? vec3(0.0, 1.0, 1.0) : ramp((e.r + e.g + e.b) / 3.0 / u_errMax);
    } else if (bad(v)) {
      c = vec3(0.0, 1.0, 1.0);
    } else if (u_mode == 1) {
      float y = dot(v, vec3(0.2126, 0.7152, 0.0722)) * u_scale;
      c = y > 0.0 ? ramp((log2(y) - float(${FALSE_LO})) / float(${FALSE_HI - FALSE_LO})) : R0;
    } else {
      v *= u_scale;
      c = vec3(srgb8(v.r), srgb8(v.g), srgb8(v.b));
    }
    o = vec4(c, 1.0);
  }`;

  function compile(type, src) {
    const sh = gl.createShader(type);
    gl.shaderSource(sh, src);
    gl.compileShader(sh);
    if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) fail('shader: ' + gl.getShaderInfoLog(sh));
    return sh;
  }
  function initGL() {
    gl = glCanvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true, alpha: false });
    if (!gl) fail('This page needs WebGL2 (a current Firefox, Chrome or Safari).');
    const max = gl.getParameter(gl.MAX_TEXTURE_SIZE);
    if (W > max || H > max) fail('The images (' + W + 'x' + H + ') exceed this GPU\'s texture size ' + max + '.');
    prog = gl.createProgram();
    gl.attachShader(prog, compile(gl.VERTEX_SHADER, VS));
    gl.attachShader(prog, compile(gl.FRAGMENT_SHADER, FS));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) fail('shader link: ' + gl.getProgramInfoLog(prog));
    gl.useProgram(prog);
    for (const n of ['u_img', 'u_ref', 'u_panel', 'u_view', 'u_size', 'u_scale', 'u_mode', 'u_errMax', 'u_eps'])
      uni[n] = gl.getUniformLocation(prog, n);
    const buf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 1, -1, -1, 1, 1, 1]), gl.STATIC_DRAW);
    const loc = gl.getAttribLocation(prog, 'a_pos');
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, 2, gl.FLOAT, false, 0, 0);
    gl.uniform1i(uni.u_img, 0);
    gl.uniform1i(uni.u_ref, 1);
    gl.uniform2i(uni.u_size, W, H);
    gl.uniform1f(uni.u_eps, D.epsilon);
  }
  function upload(k, data) {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB16F, W, H, 0, gl.RGB, gl.HALF_FLOAT, data);
    for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
    for (const p of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T]) gl.texParameteri(gl.TEXTURE_2D, p, gl.CLAMP_TO_EDGE);
    textures[k] = t;
  }
  // Draws image k into the framebuffer rectangle (x, y lower-left, w, h) with a view.
  function drawImage(k, x, y, w, h, zoom, cx, cy) {
    gl.viewport(x, y, w, h);
    gl.scissor(x, y, w, h);
    gl.uniform4f(uni.u_panel, x, y, w, h);
    gl.uniform3f(uni.u_view, zoom, cx, cy);
    gl.uniform1f(uni.u_scale, Math.pow(2, state.exposure));
    gl.uniform1i(uni.u_mode, state.mode);
    gl.uniform1f(uni.u_errMax, Math.pow(10, state.errLog));
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, textures[0]);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, textures[k]);
    gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
  }

  // ---------- layout and view ----------
  function dpr() { return window.devicePixelRatio || 1; }
  function layout() {
    const r = dpr(), cw = Math.max(1, Math.round(viewer.clientWidth * r)), ch = Math.max(1, Math.round(viewer.clientHeight * r));
    for (const c of [glCanvas, overlay]) {
      if (c.width !== cw) c.width = cw;
      if (c.height !== ch) c.height = ch;
    }
    panels = [];
    if (!state.grid) {
      panels.push({ k: state.current, x: 0, y: 0, w: cw, h: ch });
      return;
    }
    // Columns that give the largest panels for the image's aspect.
    let best = 1, bestScale = 0;
    for (let cols = 1; cols <= N; ++cols) {
      const rows = Math.ceil(N / cols), s = Math.min(cw / cols / W, ch / rows / H);
      if (s > bestScale) { bestScale = s; best = cols; }
    }
    const rows = Math.ceil(N / best), pw = Math.floor(cw / best), ph = Math.floor(ch / rows);
    for (let k = 0; k < N; ++k)
      panels.push({ k, x: (k % best) * pw, y: Math.floor(k / best) * ph, w: pw - 2, h: ph - 2 });
  }
  function fit() {
    layout();
    const p = panels[0];
    state.zoom = Math.min(p.w / W, p.h / H);
    if (state.zoom > 1) state.zoom = Math.floor(state.zoom);  // whole pixels when magnified
    state.cx = W / 2;
    state.cy = H / 2;
    redraw();
  }
  // Image coordinates of framebuffer point (px, py) (top-left origin) in panel p.
  function toImage(p, px, py) {
    return [(px - p.x - p.w / 2) / state.zoom + state.cx, (py - p.y - p.h / 2) / state.zoom + state.cy];
  }
  function toScreen(p, ix, iy) {
    return [(ix - state.cx) * state.zoom + p.x + p.w / 2, (iy - state.cy) * state.zoom + p.y + p.h / 2];
  }
  function panelAt(px, py) {
    return panels.find((p) => px >= p.x && px < p.x + p.w && py >= p.y && py < p.y + p.h) || null;
  }

  function redraw() {
    if (!state.ready || drawQueued) return;
    drawQueued = true;
    requestAnimationFrame(() => { drawQueued = false; draw(); renderCrops(); });
  }
  function draw() {
    layout();
    const fbH = glCanvas.height;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.disable(gl.SCISSOR_TEST);
    gl.viewport(0, 0, glCanvas.width, fbH);
    gl.clearColor(0.12, 0.12, 0.12, 1);
    gl.clear(gl.COLOR_BUFFER_BIT);
    gl.enable(gl.SCISSOR_TEST);
    for (const p of panels) drawImage(p.k, p.x, fbH - p.y - p.h, p.w, p.h, state.zoom, state.cx, state.cy);
    gl.disable(gl.SCISSOR_TEST);
    drawOverlay();
  }
  function drawOverlay(drag) {
    const ctx = overlay.getContext('2d'), r = dpr();
    ctx.clearRect(0, 0, overlay.width, overlay.height);
    ctx.font = Math.round(13 * r) + 'px sans-serif';
    ctx.textBaseline = 'top';
    for (const p of panels) {
      ctx.save();
      ctx.beginPath();
      ctx.rect(p.x, p.y, p.w, p.h);
      ctx.clip();
      const rects = state.crops.map((c, i) => [c, CROP_COLOURS[i % CROP_COLOURS.length]]);
      if (drag && drag.p === p) rects.push([drag.box, '#fff']);
      for (const [c, colour] of rects) {
        const a = toScreen(p, c.x0, c.y0), b = toScreen(p, c.x1, c.y1);
        ctx.strokeStyle = colour;
        ctx.lineWidth = 2 * r;
        ctx.strokeRect(a[0], a[1], b[0] - a[0], b[1] - a[1]);
      }
      const label = (p.k + 1) + '  ' + D.images[p.k].label;
      const tw = ctx.measureText(label).width;
      ctx.fillStyle = 'rgba(0,0,0,0.6)';
      ctx.fillRect(p.x, p.y, tw + 12 * r, 20 * r);
      ctx.fillStyle = p.k === state.current ? '#fff' : '#ccc';
      ctx.fillText(label, p.x + 6 * r, p.y + 4 * r);
      if (state.grid && p.k === state.current) {
        ctx.strokeStyle = '#4a86c2';
        ctx.lineWidth = 3 * r;
        ctx.strokeRect(p.x + 1, p.y + 1, p.w - 2, p.h - 2);
      }
      ctx.restore();
    }
  }

  // ---------- crops ----------
  let cropFbo = null;
  // RGBA bytes (top row first) of image k over [x0,x1)x[y0,y1), one texel per pixel.
  function renderRegion(k, x0, y0, x1, y1) {
    const w = x1 - x0, h = y1 - y0;
    if (!cropFbo) cropFbo = { fb: gl.createFramebuffer(), tex: gl.createTexture(), w: 0, h: 0 };
    gl.bindFramebuffer(gl.FRAMEBUFFER, cropFbo.fb);
    if (cropFbo.w < w || cropFbo.h < h) {
      cropFbo.w = Math.max(w, cropFbo.w);
      cropFbo.h = Math.max(h, cropFbo.h);
      gl.bindTexture(gl.TEXTURE_2D, cropFbo.tex);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, cropFbo.w, cropFbo.h, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, cropFbo.tex, 0);
    }
    gl.enable(gl.SCISSOR_TEST);
    drawImage(k, 0, 0, w, h, 1, x0 + w / 2, y0 + h / 2);
    gl.disable(gl.SCISSOR_TEST);
    const buf = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, buf);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    const out = new Uint8ClampedArray(w * h * 4);
    for (let y = 0; y < h; ++y) out.set(buf.subarray((h - 1 - y) * w * 4, (h - y) * w * 4), y * w * 4);
    return out;
  }
  function addCrop(box) {
    const c = {
      x0: Math.max(0, Math.floor(Math.min(box.x0, box.x1))), y0: Math.max(0, Math.floor(Math.min(box.y0, box.y1))),
      x1: Math.min(W, Math.ceil(Math.max(box.x0, box.x1))), y1: Math.min(H, Math.ceil(Math.max(box.y0, box.y1))),
    };
    if (c.x1 - c.x0 < 2 || c.y1 - c.y0 < 2) return;
    state.crops.push(c);
    buildCrops();
    redraw();
  }
  function buildCrops() {
    const list = $('crop-list');
    list.textContent = '';
    state.crops.forEach((c, i) => {
      const div = document.createElement('div');
      div.className = 'crop';
      div.style.borderLeftColor = CROP_COLOURS[i % CROP_COLOURS.length];
      const w = c.x1 - c.x0, h = c.y1 - c.y0, scale = Math.max(1, Math.floor(200 / Math.max(w, h)));
      const info = document.createElement('div');
      info.className = 'info';
      info.innerHTML = 'x ' + c.x0 + '&ndash;' + (c.x1 - 1) + '<br>y ' + c.y0 + '&ndash;' + (c.y1 - 1) +
        '<br>' + w + '&times;' + h + ' px<br>';
      const un = document.createElement('button');
      un.textContent = 'unpin';
      un.onclick = () => { state.crops.splice(i, 1); buildCrops(); redraw(); };
      info.appendChild(un);
      div.appendChild(info);
      c.canvases = [];
      for (let k = 0; k < N; ++k) {
        const fig = document.createElement('figure');
        const cv = document.createElement('canvas');
        cv.width = w;
        cv.height = h;
        cv.style.width = w * scale + 'px';
        cv.style.height = h * scale + 'px';
        cv.title = 'show ' + D.images[k].label;
        cv.onclick = () => select(k);
        const cap = document.createElement('figcaption');
        cap.textContent = (k + 1) + ' ' + D.images[k].label;
        fig.append(cv, cap);
        div.appendChild(fig);
        c.canvases.push(cv);
      }
      list.appendChild(div);
    });
  }
  function renderCrops() {
    for (const c of state.crops) {
      c.canvases.forEach((cv, k) => {
        const img = new ImageData(renderRegion(k, c.x0, c.y0, c.x1, c.y1), c.x1 - c.x0, c.y1 - c.y0);
        cv.getContext('2d').putImageData(img, 0, 0);
        cv.parentNode.classList.toggle('current', k === state.current);
      });
    }
  }

  // ---------- side panel ----------
  const META_FIRST = ['integrator', 'spp', 'render_seconds', 'seed', 'stop_reason', 'resolution', 'passes',
    'command_line', 'gradus_version', 'integrator_parameters'];
  function buildTabs() {
    const nav = $('tabs');
    nav.textContent = '';
    D.images.forEach((im, k) => {
      const b = document.createElement('button');
      b.innerHTML = (k < 9 ? '<span class="key">' + (k + 1) + '</span>' : '') + esc(im.label);
      b.title = im.file + (im.layer ? ' (layer ' + im.layer + ')' : '');
      b.onclick = () => select(k);
      nav.appendChild(b);
    });
  }
  function buildStats() {
    const t = $('stats');
    let h = '<tr><th class="l">image</th><th>relMSE</th><th>PSNR dB</th><th>MSE</th><th>mean</th>' +
      '<th>vs ref</th><th>spp</th><th>time s</th></tr>';
    D.images.forEach((im, k) => {
      const m = im.metrics, md = im.metadata;
      const rel = im.reference ? 'reference' : fmt(m.relmse);
      h += '<tr class="img" data-k="' + k + '"><td class="l">' + (k + 1) + ' ' + esc(im.label) + '</td><td>' + rel +
        '</td><td>' + (im.reference ? '' : fmt(m.psnr)) + '</td><td>' + (im.reference ? '' : fmt(m.mse)) +
        '</td><td>' + fmt(m.mean) + '</td><td>' +
        (im.reference || m.mean_rel_diff === null ? '' : (m.mean_rel_diff >= 0 ? '+' : '') + (100 * m.mean_rel_diff).toFixed(2) + '%') +
        '</td><td>' + esc(md.spp !== undefined ? md.spp : '') + '</td><td>' +
        (typeof md.render_seconds === 'number' ? fmt(md.render_seconds, 3) : '') + '</td></tr>';
    });
    t.innerHTML = h;
    for (const tr of t.querySelectorAll('tr.img')) tr.onclick = () => select(Number(tr.dataset.k));
    let note = 'relMSE = mean over pixels and R,G,B of (X\u2212R)\u00b2/(R\u00b2+' + D.epsilon + '); PSNR peak 1.0; ' +
      'means over R,G,B (imgtool diff\'s figures)';
    if (D.discard_fraction > 0 || D.discard_count > 0)
      note += '; trimmed: the highest ' + 100 * D.discard_fraction + '% and ' + D.discard_count + ' more pixels';
    $('metric-note').textContent = note + '.';
  }
  function buildMeta() {
    const im = D.images[state.current], md = im.metadata;
    $('meta-title').textContent = 'Metadata: ' + im.label;
    const keys = META_FIRST.filter((k) => k in md).concat(Object.keys(md).filter((k) => !META_FIRST.includes(k)).sort());
    let h = '<tr><td class="k">file</td><td class="v">' + esc(im.file) + (im.layer ? ' (layer ' + esc(im.layer) + ')' : '') + '</td></tr>';
    for (const k of keys) {
      const v = typeof md[k] === 'number' && !Number.isInteger(md[k]) ? fmt(md[k], 6) : md[k];
      h += '<tr><td class="k">' + esc(k) + '</td><td class="v">' + esc(v === null ? 'NaN/Inf' : v) + '</td></tr>';
    }
    if (!keys.length) h += '<tr><td class="k"></td><td class="v">(no metadata)</td></tr>';
    $('meta').innerHTML = h;
  }
  function drawLegend() {
    const cv = $('legend-ramp'), ctx = cv.getContext('2d');
    const grad = ctx.createLinearGradient(0, 0, cv.width, 0);
    RAMP.forEach((c, i) => grad.addColorStop(i / (RAMP.length - 1),
      'rgb(' + c.map((v) => Math.round(255 * v)).join(',') + ')'));
    ctx.fillStyle = grad;
    ctx.fillRect(0, 0, cv.width, cv.height);
    cv.style.visibility = state.mode === 0 ? 'hidden' : 'visible';
    const ev = (state.exposure >= 0 ? '+' : '') + state.exposure.toFixed(1);
    const text = [
      'sRGB: value \u00d7 2^' + ev + ', clamped to [0, 1], sRGB-encoded (as imgtool convert to PNG); cyan = NaN/Inf',
      'false colour: log2 of luminance \u00d7 2^' + ev + ', from ' + FALSE_LO + ' (black) to ' + FALSE_HI + ' (white)',
      'relative error: per-pixel relMSE, mean over R,G,B of (X\u2212R)\u00b2/(R\u00b2+' + D.epsilon + '), 0 (black) to ' +
        fmt(Math.pow(10, state.errLog), 3) + ' (white); cyan = NaN/Inf',
    ];
    $('legend-text').textContent = text[state.mode];
  }
  function updateControls() {
    $('exposure').value = state.exposure;
    $('exposure-value').textContent = (state.exposure >= 0 ? '+' : '') + state.exposure.toFixed(1) + ' EV';
    $('errmax').value = state.errLog;
    $('errmax-value').textContent = fmt(Math.pow(10, state.errLog), 3);
    $('errmax-label').style.display = state.mode === 2 ? '' : 'none';
    for (const b of document.querySelectorAll('#modes button')) b.classList.toggle('on', Number(b.dataset.mode) === state.mode);
    $('layout').classList.toggle('on', state.grid);
    $('crop-mode').classList.toggle('on', state.cropMode);
    viewer.classList.toggle('crop', state.cropMode);
    $('tabs').querySelectorAll('button').forEach((b, k) => b.classList.toggle('on', k === state.current));
    for (const tr of $('stats').querySelectorAll('tr.img')) tr.classList.toggle('current', Number(tr.dataset.k) === state.current);
    drawLegend();
  }

  // ---------- actions ----------
  function select(k) {
    if (k < 0 || k >= N) return;
    state.current = k;
    buildMeta();
    updateControls();
    redraw();
  }
  function setMode(m) { state.mode = m; updateControls(); redraw(); }
  function setExposure(ev) { state.exposure = Math.max(-12, Math.min(12, Math.round(ev * 10) / 10)); updateControls(); redraw(); }
  function zoomAbout(factor, p, px, py) {
    const z = Math.max(1 / 64, Math.min(256, state.zoom * factor));
    const [ix, iy] = toImage(p, px, py);
    state.zoom = z;
    state.cx = ix - (px - p.x - p.w / 2) / z;
    state.cy = iy - (py - p.y - p.h / 2) / z;
    redraw();
  }
  function pixelInfo(k, ix, iy) {
    const x = Math.floor(ix), y = Math.floor(iy);
    if (x < 0 || y < 0 || x >= W || y >= H) return '';
    const i = (y * W + x) * 3, v = [0, 1, 2].map((c) => halfToFloat(pixels[k][i + c]));
    const r = [0, 1, 2].map((c) => halfToFloat(pixels[0][i + c]));
    const e = [0, 1, 2].reduce((s, c) => s + (v[c] - r[c]) * (v[c] - r[c]) / (r[c] * r[c] + D.epsilon), 0) / 3;
    const f = (a) => a.map((t) => fmt(t, 5)).join(', ');
    return 'pixel (' + x + ', ' + y + ')  ' + D.images[k].label + '\nRGB ' + f(v) + '\nref ' + f(r) +
      (k ? '   relMSE ' + fmt(e, 4) : '');
  }

  function bindEvents() {
    $('exposure').addEventListener('input', (e) => setExposure(parseFloat(e.target.value)));
    $('exposure-reset').onclick = () => setExposure(D.exposure);
    $('errmax').addEventListener('input', (e) => { state.errLog = parseFloat(e.target.value); updateControls(); redraw(); });
    for (const b of document.querySelectorAll('#modes button')) b.onclick = () => setMode(Number(b.dataset.mode));
    $('layout').onclick = () => { state.grid = !state.grid; updateControls(); fit(); };
    $('fit').onclick = fit;
    $('crop-mode').onclick = () => { state.cropMode = !state.cropMode; updateControls(); };
    window.addEventListener('resize', redraw);
    document.addEventListener('keydown', (e) => {
      if (e.ctrlKey || e.metaKey || e.altKey || !state.ready) return;
      if (e.target.tagName === 'INPUT' && e.key.startsWith('Arrow')) return;  // the slider's own keys
      const k = e.key;
      if (k >= '1' && k <= '9') select(Number(k) - 1);
      else if (k === 'ArrowRight') select((state.current + 1) % N);
      else if (k === 'ArrowLeft') select((state.current + N - 1) % N);
      else if (k === 's') setMode(0);
      else if (k === 'f') setMode(1);
      else if (k === 'e') setMode(2);
      else if (k === '[') setExposure(state.exposure - 0.5);
      else if (k === ']') setExposure(state.exposure + 0.5);
      else if (k === 'g') { state.grid = !state.grid; updateControls(); fit(); }
      else if (k === 'c') { state.cropMode = !state.cropMode; updateControls(); }
      else if (k === 'Escape') { state.cropMode = false; updateControls(); }
      else if (k === '0') fit();
      else if (k === '+' || k === '=') zoomAbout(2, panels[0], panels[0].x + panels[0].w / 2, panels[0].y + panels[0].h / 2);
      else if (k === '-') zoomAbout(0.5, panels[0], panels[0].x + panels[0].w / 2, panels[0].y + panels[0].h / 2);
      else return;
      e.preventDefault();
    });
    let drag = null;
    const pos = (e) => { const b = overlay.getBoundingClientRect(), r = dpr(); return [(e.clientX - b.left) * r, (e.clientY - b.top) * r]; };
    viewer.addEventListener('mousedown', (e) => {
      if (e.button !== 0 || !state.ready) return;
      const [px, py] = pos(e), p = panelAt(px, py);
      if (!p) return;
      const cropping = state.cropMode || e.shiftKey;
      const [ix, iy] = toImage(p, px, py);
      drag = { p, px, py, cx: state.cx, cy: state.cy, crop: cropping, box: { x0: ix, y0: iy, x1: ix, y1: iy } };
      e.preventDefault();
    });
    window.addEventListener('mousemove', (e) => {
      if (!state.ready) return;
      const [px, py] = pos(e);
      if (drag && drag.crop) {
        [drag.box.x1, drag.box.y1] = toImage(drag.p, px, py);
        drawOverlay(drag);
      } else if (drag) {
        state.cx = drag.cx - (px - drag.px) / state.zoom;
        state.cy = drag.cy - (py - drag.py) / state.zoom;
        redraw();
      }
      const p = panelAt(px, py);
      if (p && e.target === overlay) $('pixel').textContent = pixelInfo(p.k, ...toImage(p, px, py)) || '\u00a0';
    });
    window.addEventListener('mouseup', () => {
      if (drag && drag.crop) addCrop(drag.box);
      drag = null;
    });
    viewer.addEventListener('wheel', (e) => {
      if (!state.ready) return;
      const [px, py] = pos(e), p = panelAt(px, py);
      if (!p) return;
      e.preventDefault();
      zoomAbout(Math.pow(2, -e.deltaY / 240), p, px, py);
    }, { passive: false });
    viewer.addEventListener('dblclick', fit);
  }

  // ---------- test hooks ----------
  // The bytes shown on screen for image pixels [[x, y], ...] of the current
  // image's panel (drawn now, read back from the canvas); null for a pixel
  // that is not visible.
  window.gradusReadPixels = function (points) {
    if (!state.ready) return points.map(() => null);
    draw();
    const p = panels.find((q) => q.k === state.current);
    const cw = glCanvas.width, ch = glCanvas.height, buf = new Uint8Array(cw * ch * 4);
    gl.readPixels(0, 0, cw, ch, gl.RGBA, gl.UNSIGNED_BYTE, buf);
    return points.map(([x, y]) => {
      const [sx, sy] = toScreen(p, x + 0.5, y + 0.5), col = Math.floor(sx), row = Math.floor(sy);
      if (col < p.x || row < p.y || col >= p.x + p.w || row >= p.y + p.h) return null;
      const i = ((ch - 1 - row) * cw + col) * 4;
      return [buf[i], buf[i + 1], buf[i + 2]];
    });
  };
  window.gradusReadPixel = (x, y) => window.gradusReadPixels([[x, y]])[0];
  window.gradusState = () => ({
    current: state.current, label: D.images[state.current].label, mode: MODES[state.mode], exposure: state.exposure,
    zoom: state.zoom, cx: state.cx, cy: state.cy, grid: state.grid, crops: state.crops.length, ready: state.ready,
  });
  window.gradusPanels = () => panels.map((p) => ({ k: p.k, x: p.x / dpr(), y: p.y / dpr(), w: p.w / dpr(), h: p.h / dpr() }));
  window.gradusSetView = (zoom, cx, cy) => { state.zoom = zoom; state.cx = cx; state.cy = cy; draw(); };

  async function main() {
    document.title = D.title;
    $('title').textContent = D.title;
    buildTabs();
    buildStats();
    buildMeta();
    bindEvents();
    updateControls();
    initGL();
    for (let k = 0; k < N; ++k) {
      status.textContent = 'loading image ' + (k + 1) + ' of ' + N + '\u2026';
      pixels[k] = await decodeImage(k);
      upload(k, pixels[k]);
    }
    status.textContent = W + '\u00d7' + H + ', ' + N + ' images';
    state.ready = true;
    fit();
    draw();
    window.gradusReady = true;
  }
  main().catch((e) => { status.textContent = String(e.message || e); status.classList.add('error'); console.error(e); });
})();
