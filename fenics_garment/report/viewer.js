// fenics-garment report: a small WebGL viewer of the contact pressure on the body and garment.
// Self-contained (no library). Data: the JSON of <script id="surface-data">, each surface's
// vertices (float32 xyz), triangles (uint32) and pressure [Pa] (float32) as base64 strings.
// Mouse: drag to rotate, wheel to zoom, double-click to reset. Touch: drag to rotate.
(function () {
  "use strict";

  // viridis at 9 evenly spaced points, linearly interpolated
  const VIRIDIS = [
    [68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 141],
    [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37],
  ];
  const NO_CONTACT = [0.80, 0.80, 0.82];
  const BACKGROUND = [1.0, 1.0, 1.0];
  const DEPTH_SHIFT = 0.01; // of the scene's radius (see draw)

  function colourOf(t) {
    const s = Math.min(Math.max(t, 0), 1) * (VIRIDIS.length - 1);
    const i = Math.min(Math.floor(s), VIRIDIS.length - 2);
    const f = s - i;
    return VIRIDIS[i].map((c, k) => (c + f * (VIRIDIS[i + 1][k] - c)) / 255);
  }

  function decode(b64, Type) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }

  function vertexNormals(v, tri) {
    const n = new Float32Array(v.length);
    for (let t = 0; t < tri.length; t += 3) {
      const a = 3 * tri[t], b = 3 * tri[t + 1], c = 3 * tri[t + 2];
      const ux = v[b] - v[a], uy = v[b + 1] - v[a + 1], uz = v[b + 2] - v[a + 2];
      const wx = v[c] - v[a], wy = v[c + 1] - v[a + 1], wz = v[c + 2] - v[a + 2];
      const nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
      for (const k of [a, b, c]) { n[k] += nx; n[k + 1] += ny; n[k + 2] += nz; }
    }
    for (let k = 0; k < n.length; k += 3) {
      const l = Math.hypot(n[k], n[k + 1], n[k + 2]) || 1;
      n[k] /= l; n[k + 1] /= l; n[k + 2] /= l;
    }
    return n;
  }

  function vertexColours(p, vmax, grey) {
    const c = new Float32Array(3 * p.length);
    for (let i = 0; i < p.length; i++) {
      const rgb = grey || !(p[i] > 0) ? NO_CONTACT : colourOf(p[i] / vmax);
      c.set(rgb, 3 * i);
    }
    return c;
  }

  // ---- 4x4 matrices, column-major as WebGL wants them ----
  function multiply(a, b) {
    const m = new Float32Array(16);
    for (let i = 0; i < 4; i++) {
      for (let j = 0; j < 4; j++) {
        let s = 0;
        for (let k = 0; k < 4; k++) s += a[k * 4 + i] * b[j * 4 + k];
        m[j * 4 + i] = s;
      }
    }
    return m;
  }

  function perspective(fovy, aspect, near, far) {
    const f = 1 / Math.tan(fovy / 2), m = new Float32Array(16);
    m[0] = f / aspect; m[5] = f; m[10] = (far + near) / (near - far); m[11] = -1;
    m[14] = (2 * far * near) / (near - far);
    return m;
  }

  // the camera orbits the centre; z is up, the body faces -y (yaw 0: seen from the front)
  function basis(cam) {
    const cy = Math.cos(cam.yaw), sy = Math.sin(cam.yaw);
    const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    const back = [sy * cp, -cy * cp, sp]; // from the centre towards the eye
    return {
      right: [cy, sy, 0], up: [-sy * sp, cy * sp, cp], back: back,
      eye: cam.centre.map((c, k) => c + cam.distance * back[k]),
    };
  }

  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

  function view(cam) {
    const { right, up, back, eye: e } = basis(cam);
    return new Float32Array([
      right[0], up[0], back[0], 0, right[1], up[1], back[1], 0, right[2], up[2], back[2], 0,
      -dot(right, e), -dot(up, e), -dot(back, e), 1,
    ]);
  }

  // The surface point under a pixel (nx, ny in [-1, 1]): the nearest triangle the ray through
  // it hits (Moller-Trumbore), each mesh's distance lengthened by its bias (see draw).
  function pick(cam, fov, aspect, nx, ny, meshes) {
    const { right, up, back, eye } = basis(cam);
    const tf = Math.tan(fov / 2);
    const d = [0, 1, 2].map((k) => -back[k] + nx * tf * aspect * right[k] + ny * tf * up[k]);
    let best = null;
    for (const [m, bias] of meshes) {
      const v = m.surface.vertices, tri = m.surface.triangles;
      for (let t = 0; t < tri.length; t += 3) {
        const a = 3 * tri[t], b = 3 * tri[t + 1], c = 3 * tri[t + 2];
        const e1 = [v[b] - v[a], v[b + 1] - v[a + 1], v[b + 2] - v[a + 2]];
        const e2 = [v[c] - v[a], v[c + 1] - v[a + 1], v[c + 2] - v[a + 2]];
        const h = [d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]];
        const det = dot(e1, h);
        if (Math.abs(det) < 1e-20) continue;
        const sv = [eye[0] - v[a], eye[1] - v[a + 1], eye[2] - v[a + 2]];
        const u = dot(sv, h) / det;
        if (u < 0 || u > 1) continue;
        const q = [sv[1] * e1[2] - sv[2] * e1[1], sv[2] * e1[0] - sv[0] * e1[2], sv[0] * e1[1] - sv[1] * e1[0]];
        const w = dot(d, q) / det;
        if (w < 0 || u + w > 1) continue;
        const dist = dot(e2, q) / det + bias;
        if (dist > 0 && (!best || dist < best.dist)) {
          const p = m.surface.pressure;
          best = { dist: dist, mesh: m, pressure: (1 - u - w) * p[tri[t]] + u * p[tri[t + 1]] + w * p[tri[t + 2]] };
        }
      }
    }
    return best;
  }

  const VERTEX_SHADER = `
    attribute vec3 position; attribute vec3 normal; attribute vec3 colour;
    uniform mat4 projection; uniform mat4 modelView; uniform float depthShift;
    varying vec3 vColour; varying vec3 vNormal;
    void main() {
      vColour = colour;
      vNormal = (modelView * vec4(normal, 0.0)).xyz;
      vec4 eye = modelView * vec4(position, 1.0);
      eye.z -= depthShift;  // pushed away from the eye: the garment lying on it stays in front
      gl_Position = projection * eye;
    }`;
  const FRAGMENT_SHADER = `
    precision mediump float;
    varying vec3 vColour; varying vec3 vNormal;
    void main() {
      vec3 n = normalize(vNormal);
      float light = 0.35 + 0.65 * abs(dot(n, normalize(vec3(0.3, 0.5, 1.0))));
      gl_FragColor = vec4(vColour * light, 1.0);
    }`;

  function compile(gl, type, source) {
    const s = gl.createShader(type);
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }

  function program(gl) {
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, VERTEX_SHADER));
    gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, FRAGMENT_SHADER));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  }

  function buffer(gl, target, data) {
    const b = gl.createBuffer();
    gl.bindBuffer(target, b);
    gl.bufferData(target, data, gl.STATIC_DRAW);
    return b;
  }

  // one surface on the GPU; without 32-bit indices (plain WebGL 1) it is drawn unindexed
  function upload(gl, surface, wide) {
    const v = surface.vertices, tri = surface.triangles, n = vertexNormals(v, tri);
    const mesh = { count: tri.length, surface: surface, indexed: wide || v.length / 3 < 65536 };
    let pos = v, nor = n, idx = null;
    if (mesh.indexed) {
      idx = wide ? tri : new Uint16Array(tri);
    } else {
      pos = new Float32Array(3 * tri.length); nor = new Float32Array(3 * tri.length);
      tri.forEach((i, k) => { pos.set(v.subarray(3 * i, 3 * i + 3), 3 * k); nor.set(n.subarray(3 * i, 3 * i + 3), 3 * k); });
    }
    mesh.position = buffer(gl, gl.ARRAY_BUFFER, pos);
    mesh.normal = buffer(gl, gl.ARRAY_BUFFER, nor);
    mesh.colour = gl.createBuffer();
    if (idx) {
      mesh.index = buffer(gl, gl.ELEMENT_ARRAY_BUFFER, idx);
      mesh.type = wide ? gl.UNSIGNED_INT : gl.UNSIGNED_SHORT;
    }
    return mesh;
  }

  function setColours(gl, mesh, vmax, grey) {
    let c = vertexColours(mesh.surface.pressure, vmax, grey);
    if (!mesh.indexed) {
      const tri = mesh.surface.triangles, e = new Float32Array(3 * tri.length);
      tri.forEach((i, k) => e.set(c.subarray(3 * i, 3 * i + 3), 3 * k));
      c = e;
    }
    gl.bindBuffer(gl.ARRAY_BUFFER, mesh.colour);
    gl.bufferData(gl.ARRAY_BUFFER, c, gl.STATIC_DRAW);
  }

  function bounds(surfaces) {
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const s of surfaces) {
      const v = s.vertices;
      for (let i = 0; i < v.length; i += 3) {
        for (let k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], v[i + k]); hi[k] = Math.max(hi[k], v[i + k]); }
      }
    }
    const centre = lo.map((l, k) => 0.5 * (l + hi[k]));
    return { centre: centre, radius: 0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1 };
  }

  function drawColourBar(canvas, vmax) {
    const ctx = canvas.getContext("2d"), w = canvas.width, h = canvas.height;
    const top = 10, bottom = h - 40, x0 = 8, bw = 18;
    ctx.clearRect(0, 0, w, h);
    for (let y = top; y <= bottom; y++) {
      const c = colourOf((bottom - y) / (bottom - top)).map((v) => Math.round(255 * v));
      ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
      ctx.fillRect(x0, y, bw, 1);
    }
    ctx.fillStyle = "#222"; ctx.font = "12px sans-serif"; ctx.textBaseline = "middle";
    for (let k = 0; k <= 4; k++) {
      const y = bottom - (k / 4) * (bottom - top);
      ctx.fillRect(x0 + bw, y, 4, 1);
      ctx.fillText((vmax * k / 4).toPrecision(2) + (k === 4 ? "+" : ""), x0 + bw + 7, y);
    }
    ctx.fillText("kPa", x0, bottom + 14);
    const g = NO_CONTACT.map((v) => Math.round(255 * v));
    ctx.fillStyle = `rgb(${g[0]},${g[1]},${g[2]})`;
    ctx.fillRect(x0, bottom + 24, bw, 12);
    ctx.fillStyle = "#222"; ctx.fillText("no contact", x0 + bw + 7, bottom + 30);
  }

  function start(root) {
    const data = JSON.parse(document.getElementById(root.dataset.source).textContent);
    const canvas = root.querySelector("canvas.view");
    const gl = canvas.getContext("webgl", { preserveDrawingBuffer: true, antialias: true });
    if (!gl) {
      root.querySelector(".status").textContent = "WebGL is not available in this browser: the 3D view cannot be shown.";
      return;
    }
    const wide = !!gl.getExtension("OES_element_index_uint");
    const surfaces = {};
    for (const name of Object.keys(data.surfaces)) {
      const d = data.surfaces[name];
      surfaces[name] = upload(gl, {
        vertices: decode(d.vertices, Float32Array),
        triangles: decode(d.triangles, Uint32Array),
        pressure: decode(d.pressure, Float32Array),
      }, wide);
    }
    const prog = program(gl);
    const loc = {
      position: gl.getAttribLocation(prog, "position"), normal: gl.getAttribLocation(prog, "normal"),
      colour: gl.getAttribLocation(prog, "colour"),
      projection: gl.getUniformLocation(prog, "projection"), modelView: gl.getUniformLocation(prog, "modelView"),
      depthShift: gl.getUniformLocation(prog, "depthShift"),
    };
    const fit = bounds(Object.values(surfaces).map((m) => m.surface));
    const fov = 0.6;
    const home = { yaw: 0.35, pitch: 0.25, distance: 1.15 * fit.radius / Math.sin(fov / 2), centre: fit.centre };
    const cam = Object.assign({}, home);
    const select = root.querySelector("select.show");
    let visible = [];
    let pending = false;

    function applyMode() {
      const mode = select.value;
      visible = [];
      if (surfaces.body) {
        setColours(gl, surfaces.body, data.vmax_kPa * 1e3, mode === "garment");
        visible.push(surfaces.body);
      }
      if (surfaces.garment && mode !== "body") {
        setColours(gl, surfaces.garment, data.vmax_kPa * 1e3, false);
        visible.push(surfaces.garment);
      }
      redraw();
    }

    function draw() {
      pending = false;
      const dpr = window.devicePixelRatio || 1;
      const w = Math.round(canvas.clientWidth * dpr), h = Math.round(canvas.clientHeight * dpr);
      if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
      gl.viewport(0, 0, w, h);
      gl.clearColor(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 1);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      gl.enable(gl.DEPTH_TEST);
      gl.useProgram(prog);
      const near = Math.max(cam.distance - 2 * fit.radius, cam.distance * 0.01);
      gl.uniformMatrix4fv(loc.projection, false, perspective(fov, w / Math.max(h, 1), near, cam.distance + 2 * fit.radius));
      gl.uniformMatrix4fv(loc.modelView, false, view(cam));
      let drawn = 0;
      for (const m of visible) {
        // the garment's flat cells cut chords under the curved skin: the body is drawn a
        // little further back whenever the garment is shown
        const behind = m === surfaces.body && visible.length > 1;
        gl.uniform1f(loc.depthShift, behind ? DEPTH_SHIFT * fit.radius : 0.0);
        for (const [name, b] of [["position", m.position], ["normal", m.normal], ["colour", m.colour]]) {
          gl.bindBuffer(gl.ARRAY_BUFFER, b);
          gl.enableVertexAttribArray(loc[name]);
          gl.vertexAttribPointer(loc[name], 3, gl.FLOAT, false, 0, 0);
        }
        if (m.indexed) {
          gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, m.index);
          gl.drawElements(gl.TRIANGLES, m.count, m.type, 0);
        } else {
          gl.drawArrays(gl.TRIANGLES, 0, m.count);
        }
        drawn += m.count / 3;
      }
      canvas.dataset.triangles = String(drawn);
    }

    function redraw() {
      if (!pending) { pending = true; requestAnimationFrame(draw); }
    }

    const readout = root.querySelector(".readout");
    function hover(e) {
      const r = canvas.getBoundingClientRect();
      const nx = (2 * (e.clientX - r.left)) / r.width - 1, ny = 1 - (2 * (e.clientY - r.top)) / r.height;
      const shift = DEPTH_SHIFT * fit.radius;
      const meshes = visible.map((m) => [m, m === surfaces.body && visible.length > 1 ? shift : 0]);
      const hit = pick(cam, fov, r.width / r.height, nx, ny, meshes);
      const name = hit && (hit.mesh === surfaces.body ? "body" : "garment");
      readout.textContent = hit ? `${name}: ${(hit.pressure * 1e-3).toFixed(3)} kPa` : "";
    }

    let drag = null;
    let hoverPending = false;
    canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener("pointerup", () => { drag = null; });
    canvas.addEventListener("pointerleave", () => { readout.textContent = ""; });
    canvas.addEventListener("pointermove", (e) => {
      if (!drag) {
        if (!hoverPending) {
          hoverPending = true;
          requestAnimationFrame(() => { hoverPending = false; hover(e); });
        }
        return;
      }
      cam.yaw -= 0.01 * (e.clientX - drag[0]);
      cam.pitch = Math.min(1.5, Math.max(-1.5, cam.pitch + 0.01 * (e.clientY - drag[1])));
      drag = [e.clientX, e.clientY];
      redraw();
    });
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      cam.distance = Math.min(20 * fit.radius, Math.max(0.2 * fit.radius, cam.distance * Math.exp(0.001 * e.deltaY)));
      redraw();
    }, { passive: false });
    canvas.addEventListener("dblclick", () => { Object.assign(cam, home); redraw(); });
    root.querySelectorAll("button[data-yaw]").forEach((b) => b.addEventListener("click", () => {
      Object.assign(cam, home, { yaw: parseFloat(b.dataset.yaw), pitch: 0.1 });
      redraw();
    }));
    select.addEventListener("change", applyMode);
    window.addEventListener("resize", redraw);
    drawColourBar(root.querySelector("canvas.colourbar"), data.vmax_kPa);
    applyMode();
    draw();
  }

  document.querySelectorAll(".viewer3d").forEach((root) => {
    try {
      start(root);
    } catch (err) {
      root.querySelector(".status").textContent = "The 3D view failed: " + err.message;
      throw err;
    }
  });
})();
