// Level of detail for the site's scene: two levels per unit (a city's temple, a street column,
// one temple scene), chosen from the camera each time it moves.
//
// * The far level of every detailed mesh is made here, at load, by vertex clustering: each
//   vertex moves to the mean of the vertices in its cube of side `cell` (1/DIVISIONS of the
//   largest named unit's bounding diameter) and the triangles that collapse are dropped. A merged
//   mesh (the exporter's static copies, `instances` in its extras, equal vertex and index runs
//   per copy) keeps each copy's triangles apart, so its copies switch one by one.
// * A unit is drawn in full when its far level would be off by more than one pixel at its
//   nearest point (cell × pixels per radian / distance > 1) — named units (a city's temples)
//   first, the one nearest the camera's `target` (the orbit target; in walk mode the eye)
//   first among them — while the triangles drawn stay within `budget` (the first in full
//   whatever the budget when its far level would be off by more than MUST_PX); else its far
//   level.
// * Items (an instance of a GPU-instanced mesh, a copy of a merged mesh, a plain mesh) outside
//   the view are not drawn (a merged mesh's copies only as a whole); the drawn ones are packed
//   at the front of the instance (or index) buffer, so `resolve` maps a hit's
//   instanceId/faceIndex back to the item. A merged mesh whose copies belong to several units
//   becomes GPU-instanced first (`instanceCopies`).
import * as THREE from "three";

export const DIVISIONS = 64;
// the first unit's far level off by more than this (px): drawn in full whatever the budget
export const MUST_PX = 4;

function trianglesOf(g) {
  return (g.index ? g.index.count : g.attributes.position.count) / 3;
}

// a coarse copy of `geom` (vertex clustering at `cell`); `copies` runs of triangles kept apart:
// returns { geometry, start } with copy c's triangles at [start[c], start[c + 1])
export function cluster(geom, cell, copies = 1) {
  const pos = geom.attributes.position, nrm = geom.attributes.normal, uv = geom.attributes.uv;
  const n = pos.count;
  const idx = geom.index ? geom.index.array : Uint32Array.from({ length: n }, (_, i) => i);
  const tris = idx.length / 3, per = tris / copies;
  const remap = new Int32Array(n), cells = new Map();
  const P = [], N = [], U = [], C = [];
  for (let v = 0; v < n; v++) {
    const x = pos.getX(v), y = pos.getY(v), z = pos.getZ(v);
    const k = ((Math.floor(x / cell) & 0xffff) * 65536 + (Math.floor(y / cell) & 0xffff)) * 65536 + (Math.floor(z / cell) & 0xffff);
    let id = cells.get(k);
    if (id === undefined) {
      id = C.length;
      cells.set(k, id);
      C.push(0);
      P.push(0, 0, 0);
      N.push(0, 0, 0);
      if (uv) U.push(uv.getX(v), uv.getY(v));
    }
    C[id]++;
    P[3 * id] += x; P[3 * id + 1] += y; P[3 * id + 2] += z;
    if (nrm) { N[3 * id] += nrm.getX(v); N[3 * id + 1] += nrm.getY(v); N[3 * id + 2] += nrm.getZ(v); }
    remap[v] = id;
  }
  const out = [], start = new Int32Array(copies + 1), seen = new Set();
  for (let c = 0; c < copies; c++) {
    start[c] = out.length / 3;
    seen.clear();
    for (let t = Math.round(c * per); t < Math.round((c + 1) * per); t++) {
      let a = remap[idx[3 * t]], b = remap[idx[3 * t + 1]], d = remap[idx[3 * t + 2]];
      if (a === b || b === d || a === d) continue;
      while (a > b || a > d) [a, b, d] = [b, d, a]; // the same triangle, whichever vertex first
      const key = `${a},${b},${d}`;
      if (seen.has(key)) continue;
      seen.add(key);
      out.push(a, b, d);
    }
  }
  start[copies] = out.length / 3;
  const g = new THREE.BufferGeometry();
  const p = new Float32Array(P.length), q = new Float32Array(N.length);
  for (let i = 0; i < C.length; i++) {
    for (let j = 0; j < 3; j++) p[3 * i + j] = P[3 * i + j] / C[i];
    const l = Math.hypot(N[3 * i], N[3 * i + 1], N[3 * i + 2]) || 1;
    for (let j = 0; j < 3; j++) q[3 * i + j] = N[3 * i + j] / l;
  }
  g.setAttribute("position", new THREE.BufferAttribute(p, 3));
  g.setAttribute("normal", new THREE.BufferAttribute(q, 3));
  if (uv) g.setAttribute("uv", new THREE.BufferAttribute(new Float32Array(U), 2));
  g.setIndex(new THREE.BufferAttribute(new Uint32Array(out), 1));
  return { geometry: g, start };
}

// a geometry sharing `g`'s vertex attributes with an index of its own
function ownIndex(g) {
  const out = new THREE.BufferGeometry();
  for (const [k, a] of Object.entries(g.attributes)) out.setAttribute(k, a);
  out.setIndex(new THREE.BufferAttribute(g.index.array.slice(), 1));
  out.boundingSphere = g.boundingSphere;
  return out;
}

function instancesOf(m) {
  if (Array.isArray(m.userData.instances)) return m.userData.instances;
  const p = m.parent;
  return p && Array.isArray(p.userData.instances) && p.children.every((c) => c.isMesh) ? p.userData.instances : null;
}

// the unit of a prim path: the longest of `unitPaths` holding it, else a point instancer's
// instance (the path to its "]"), else the path itself (`fallback` when there is none)
function unitFinder(unitPaths) {
  const units = [...unitPaths].sort((a, b) => b.length - a.length);
  return (path, fallback) => {
    if (!path) return fallback;
    const u = units.find((p) => path === p || path.startsWith(p + "/") || path.startsWith(p + "["));
    if (u) return u;
    const i = path.indexOf("]");
    return i >= 0 ? path.slice(0, i + 1) : path;
  };
}

// A merged mesh whose copies belong to several units (a city's street column shafts, its stoa
// bays) becomes a GPU-instanced mesh of its first copy, so its copies switch level and leave
// the view one by one without rewriting a large index: copy i's vertices are copy 0's under
// an affine map (the exporter's relative matrix), recovered here by least squares and kept
// only where it reproduces every vertex (a mirrored copy keeps the mesh merged).
export function instanceCopies(root, unitPaths) {
  const unitOf = unitFinder(unitPaths), found = [];
  root.traverse((m) => m.isMesh && !m.isInstancedMesh && Array.isArray(m.userData.instances) && found.push(m));
  for (const m of found) {
    const inst = m.userData.instances, n = inst.length, g = m.geometry, pos = g.attributes.position;
    if (n < 2 || new Set(inst.map((x) => unitOf(x.path, ""))).size < 2) continue;
    if (!g.index || g.index.count % (3 * n) || pos.count % n) continue;
    if (Object.values(g.attributes).some((a) => a.isInterleavedBufferAttribute)) continue;
    const nv = pos.count / n, ni = g.index.count / n, P = pos.array;
    const idx = g.index.array;
    let ok = true;
    for (let k = 0; k < ni && ok; k++) ok = idx[k] < nv && idx[(n - 1) * ni + k] === idx[k] + (n - 1) * nv;
    if (!ok) continue;
    const centre = (i) => {
      const c = [0, 0, 0];
      for (let v = i * nv; v < (i + 1) * nv; v++) for (let j = 0; j < 3; j++) c[j] += P[3 * v + j] / nv;
      return c;
    };
    const c0 = centre(0);
    const A = new THREE.Matrix3().set(0, 0, 0, 0, 0, 0, 0, 0, 0), a = A.elements;
    for (let v = 0; v < nv; v++)
      for (let r = 0; r < 3; r++) for (let c = 0; c < 3; c++) a[3 * c + r] += (P[3 * v + r] - c0[r]) * (P[3 * v + c] - c0[c]);
    if (Math.abs(A.determinant()) < 1e-12) continue;
    A.invert();
    const size = Math.max(...[0, 1, 2].map((j) => Math.abs(pos.array[j]))) + 1;
    const mats = [];
    for (let i = 0; i < n && ok; i++) {
      const ci = centre(i), B = new THREE.Matrix3().set(0, 0, 0, 0, 0, 0, 0, 0, 0), b = B.elements;
      for (let v = 0; v < nv; v++)
        for (let r = 0; r < 3; r++)
          for (let c = 0; c < 3; c++) b[3 * c + r] += (P[3 * v + r] - c0[r]) * (P[3 * (i * nv + v) + c] - ci[c]);
      const L = new THREE.Matrix3().multiplyMatrices(A, B).elements; // row vectors: x_i = x_0 L + t
      const l = (r, c) => L[3 * c + r];
      const t = [0, 1, 2].map((c) => ci[c] - (c0[0] * l(0, c) + c0[1] * l(1, c) + c0[2] * l(2, c)));
      const M = new THREE.Matrix4().set(
        l(0, 0), l(1, 0), l(2, 0), t[0], l(0, 1), l(1, 1), l(2, 1), t[1], l(0, 2), l(1, 2), l(2, 2), t[2], 0, 0, 0, 1);
      ok = M.determinant() > 0;
      for (let v = 0; v < nv && ok; v++) {
        const q = new THREE.Vector3(P[3 * v], P[3 * v + 1], P[3 * v + 2]).applyMatrix4(M);
        const w = 3 * (i * nv + v);
        ok = Math.abs(q.x - P[w]) + Math.abs(q.y - P[w + 1]) + Math.abs(q.z - P[w + 2]) < 1e-4 * size;
      }
      mats.push(M);
    }
    if (!ok) continue;
    const one = new THREE.BufferGeometry();
    for (const [k, att] of Object.entries(g.attributes))
      one.setAttribute(k, new THREE.BufferAttribute(att.array.slice(0, nv * att.itemSize), att.itemSize, att.normalized));
    one.setIndex(new THREE.BufferAttribute(idx.slice(0, ni), 1));
    const im = new THREE.InstancedMesh(one, m.material, n);
    mats.forEach((mx, i) => im.setMatrixAt(i, mx));
    im.name = m.name;
    im.userData = m.userData;
    im.position.copy(m.position);
    im.quaternion.copy(m.quaternion);
    im.scale.copy(m.scale);
    const parent = m.parent, at = parent.children.indexOf(m);
    parent.remove(m);
    parent.add(im);
    parent.children.splice(parent.children.indexOf(im), 1);
    parent.children.splice(at, 0, im);
  }
}

export function createLod(root, unitPaths, { budget }) {
  root.updateMatrixWorld(true);
  const units = [...unitPaths];
  const unitOf = unitFinder(unitPaths);
  const groupIndex = new Map(), groups = [];
  const groupOf = (key) => {
    if (!groupIndex.has(key)) {
      groupIndex.set(key, groups.length);
      groups.push({ key, box: new THREE.Box3(), sphere: new THREE.Sphere(), full: 0, proxy: 0, level: 1 });
    }
    return groupIndex.get(key);
  };
  const pathOf = (o) => {
    for (; o; o = o.parent) if (o.userData && o.userData.path) return o.userData.path;
    return "";
  };
  const meshes = [];
  root.traverse((o) => o.isMesh && meshes.push(o));
  const drawables = [], byMesh = new Map();
  const s = new THREE.Sphere(), box = new THREE.Box3(), v = new THREE.Vector3();
  for (const m of meshes) {
    const g = m.geometry;
    if (!g.boundingSphere) g.computeBoundingSphere();
    const inst = instancesOf(m);
    const tris = trianglesOf(g);
    const d = { src: m, proxy: null, n: 1, per: tris, kind: "single", hidden: new Uint8Array(1), colours: null };
    if (m.isInstancedMesh) {
      d.kind = "instanced";
      d.n = m.userData.matrices.length;
      d.mats = new Float32Array(16 * d.n);
      m.userData.matrices.forEach((mx, i) => d.mats.set(mx.elements, 16 * i));
    } else if (inst && inst.length > 1 && g.index && tris % inst.length === 0 && g.attributes.position.count % inst.length === 0) {
      d.kind = "merged";
      d.n = inst.length;
      d.per = tris / d.n;
      d.fullIndex = g.index.array.slice();
      m.geometry = ownIndex(g); // nodes laid out alike share a geometry: each packs its own
    }
    d.hidden = new Uint8Array(d.n);
    d.sphere = new Float32Array(4 * d.n);
    d.group = new Int32Array(d.n);
    const nv = g.attributes.position.count / d.n;
    for (let i = 0; i < d.n; i++) {
      if (d.kind === "instanced") s.copy(g.boundingSphere).applyMatrix4(m.userData.matrices[i]);
      else if (d.kind === "merged") {
        box.makeEmpty();
        for (let k = i * nv; k < (i + 1) * nv; k++) box.expandByPoint(v.fromBufferAttribute(g.attributes.position, k));
        box.getBoundingSphere(s);
      } else s.copy(g.boundingSphere);
      s.applyMatrix4(m.matrixWorld);
      d.sphere.set([s.center.x, s.center.y, s.center.z, s.radius], 4 * i);
      const p = inst && d.kind !== "single" ? (inst[i] || {}).path : pathOf(m);
      const gi = groupOf(unitOf(p, m.uuid));
      d.group[i] = gi;
      groups[gi].box.union(s.getBoundingBox(box));
      groups[gi].full += d.per;
    }
    // the world scale of the mesh's geometry (instances of a city's temple are scaled)
    d.scale = d.sphere[3] / (g.boundingSphere.radius || 1);
    drawables.push(d);
    byMesh.set(m, d);
  }
  // the cell: from the named units (a city's temples, not its ground), else from them all
  let diameter = 0;
  const named = groups.some((g) => units.includes(g.key));
  for (const gr of groups) {
    gr.box.getBoundingSphere(gr.sphere);
    gr.named = units.includes(gr.key);
    if (!named || units.includes(gr.key)) diameter = Math.max(diameter, 2 * gr.sphere.radius);
  }
  const cell = diameter / DIVISIONS;
  // the far levels: a plain mesh drawn as it is where clustering saves less than half
  const far = new THREE.Group();
  far.name = "lod-far";
  const made = new Map(); // geometries shared by several nodes are clustered once
  for (const d of drawables) {
    const m = d.src, copies = d.kind === "merged" ? d.n : 1;
    const pos = m.geometry.attributes.position, key = `${copies},${(cell / (d.scale || 1)).toPrecision(3)}`;
    if (!made.has(pos)) made.set(pos, new Map());
    if (!made.get(pos).has(key)) made.get(pos).set(key, cluster(m.geometry, cell / (d.scale || 1), copies));
    const c = made.get(pos).get(key);
    const ptris = c.start[c.start.length - 1];
    if (ptris > 0.5 * trianglesOf(m.geometry)) {
      for (let i = 0; i < d.n; i++) groups[d.group[i]].proxy += d.per;
      continue;
    }
    d.start = c.start;
    if (d.kind === "instanced") {
      d.proxy = new THREE.InstancedMesh(c.geometry, m.material, d.n);
      m.frustumCulled = false;
    } else {
      d.proxy = new THREE.Mesh(ownIndex(c.geometry), m.material);
      d.proxyIndex = c.geometry.index.array;
    }
    d.proxy.frustumCulled = false;
    d.proxy.matrixAutoUpdate = false;
    d.proxy.matrix.copy(m.matrixWorld);
    d.proxy.name = m.name + " (far)";
    d.proxy.userData.lodSource = m;
    far.add(d.proxy);
    for (let i = 0; i < d.n; i++) {
      groups[d.group[i]].proxy += d.kind === "merged" ? c.start[i + 1] - c.start[i] : ptris;
    }
  }
  const state = { dirty: true, last: new Float64Array(36) };

  // write the items `list` of drawable d into mesh `o` (its full or far level)
  function pack(d, o, list, isProxy) {
    if (d.kind === "instanced") {
      const arr = o.instanceMatrix.array;
      for (let j = 0; j < list.length; j++) arr.set(d.mats.subarray(16 * list[j], 16 * list[j] + 16), 16 * j);
      o.count = list.length;
      o.instanceMatrix.needsUpdate = true;
      if (d.colours) {
        if (!o.instanceColor || o.instanceColor.count < d.n)
          o.instanceColor = new THREE.InstancedBufferAttribute(new Float32Array(3 * d.n), 3);
        const ca = o.instanceColor.array;
        for (let j = 0; j < list.length; j++) ca.set(d.colours.subarray(3 * list[j], 3 * list[j] + 3), 3 * j);
        o.instanceColor.needsUpdate = true;
      }
      o.boundingSphere = null;
      o.boundingBox = null;
      o.visible = list.length > 0;
    } else if (d.kind === "merged") {
      const src = isProxy ? d.proxyIndex : d.fullIndex, dst = o.geometry.index.array;
      let at = 0;
      const firsts = [];
      const all = list.length === d.n;
      if (all && o.userData.lodAll) { // as it was: no upload
        o.userData.lodItems = list;
        o.visible = true;
        return;
      }
      o.userData.lodAll = all;
      for (const i of list) {
        const a = isProxy ? 3 * d.start[i] : 3 * d.per * i, b = isProxy ? 3 * d.start[i + 1] : 3 * d.per * (i + 1);
        firsts.push(at / 3);
        dst.set(src.subarray(a, b), at);
        at += b - a;
      }
      o.userData.lodFirsts = firsts;
      o.geometry.setDrawRange(0, at);
      o.geometry.index.clearUpdateRanges();
      o.geometry.index.addUpdateRange(0, at);
      o.geometry.index.needsUpdate = true;
      o.visible = at > 0;
    } else o.visible = list.length > 0;
    o.userData.lodItems = list;
  }

  function update(camera, heightPx, target) {
    camera.updateMatrixWorld();
    const key = [...camera.matrixWorld.elements, ...camera.projectionMatrix.elements, heightPx, ...target.toArray()];
    if (!state.dirty && key.every((x, i) => x === state.last[i])) return;
    state.last.set(key);
    state.dirty = false;
    const frustum = new THREE.Frustum().setFromProjectionMatrix(
      new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse));
    const pxPerRadian = heightPx / 2 / Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
    const eye = camera.position;
    let used = 0;
    const cands = [];
    for (const gr of groups) {
      gr.level = gr.proxy < gr.full ? 0 : 1; // one level only: drawn as it is
      gr.inView = frustum.intersectsSphere(gr.sphere);
      if (!gr.inView) continue;
      used += gr.proxy;
      if (gr.level) continue;
      gr.distance = Math.max(0, eye.distanceTo(gr.sphere.center) - gr.sphere.radius);
      gr.priority = Math.max(0, target.distanceTo(gr.sphere.center) - gr.sphere.radius);
      gr.error = (cell * pxPerRadian) / gr.distance; // how far off its far level is (px)
      if (gr.error > 1) cands.push(gr);
    }
    // named units (a city's temples) before the rest (its street columns, stoa bays)
    cands.sort((a, b) => b.named - a.named || a.priority - b.priority || a.distance - b.distance);
    for (const [k, gr] of cands.entries()) {
      if ((k > 0 || gr.error <= MUST_PX) && used + gr.full - gr.proxy > budget) continue;
      gr.level = 1;
      used += gr.full - gr.proxy;
    }
    const sp = new THREE.Sphere();
    for (const d of drawables) {
      const near = [], farList = [];
      for (let i = 0; i < d.n; i++) {
        if (d.hidden[i]) continue;
        if (d.kind !== "merged") {
          // a merged mesh's copies are not culled one by one: that would rewrite its index
          sp.center.fromArray(d.sphere, 4 * i);
          sp.radius = d.sphere[4 * i + 3];
          if (!frustum.intersectsSphere(sp)) continue;
        }
        (groups[d.group[i]].level || !d.proxy ? near : farList).push(i);
      }
      const same = (a, b) => a && a.length === b.length && a.every((x, j) => x === b[j]);
      if (!same(d.src.userData.lodItems, near)) pack(d, d.src, near, false);
      if (d.proxy) {
        d.proxy.material = d.src.material;
        if (!same(d.proxy.userData.lodItems, farList) || d.coloursChanged) pack(d, d.proxy, farList, true);
      }
      if (d.coloursChanged && d.kind === "instanced") pack(d, d.src, near, false);
      d.coloursChanged = false;
    }
  }

  // the mesh and item a raycast hit stands for
  function resolve(hit) {
    const o = hit.object, m = o.userData.lodSource || o, d = byMesh.get(m);
    if (!d) return { object: o, id: hit.instanceId };
    const list = o.userData.lodItems || [];
    if (d.kind === "instanced") return { object: m, id: list[hit.instanceId] };
    if (d.kind === "merged") {
      const firsts = o.userData.lodFirsts || [];
      let j = 0;
      while (j + 1 < firsts.length && firsts[j + 1] <= hit.faceIndex) j++;
      return { object: m, id: list[j] };
    }
    return { object: m, id: undefined };
  }

  return {
    far, cell, budget, groups, update, resolve,
    of: (m) => byMesh.get(m),
    invalidate: () => (state.dirty = true),
    setHidden(m, i, on) {
      const d = byMesh.get(m);
      if (d) d.hidden[i] = on ? 1 : 0;
    },
    setColour(m, i, colour) {
      const d = byMesh.get(m);
      if (!d.colours) d.colours = new Float32Array(3 * d.n).fill(1);
      colour.toArray(d.colours, 3 * i);
      d.coloursChanged = true;
    },
    stats: () => ({
      cell, budget,
      groups: groups.map((g) => ({ key: g.key, level: g.level, inView: g.inView, full: g.full, proxy: g.proxy,
        centre: g.sphere.center.toArray(), radius: g.sphere.radius })),
    }),
  };
}
