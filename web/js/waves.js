// Elastic wave speeds of a scene's material (reference-solutions.md), for the reference
// lines of the crack-speed plots. Nothing is hard-coded for a particular material.

/**
 * Rayleigh speed: x = (c_R/c_S)² is the root in (0, 1) of
 * (2 − x)² = 4·sqrt(1 − x)·sqrt(1 − κx), κ = (c_S/c_L)². Solved by bisection (exact to
 * double precision, no fitted approximation). f < 0 just above the trivial root x = 0 and
 * f(1) = 1 > 0, so the bracket starts at (ε, 1).
 */
export function rayleighSpeed(cL, cS) {
  const kappa = (cS / cL) ** 2;
  const f = (x) => (2 - x) ** 2 - 4 * Math.sqrt(1 - x) * Math.sqrt(1 - kappa * x);
  let lo = 1e-9, hi = 1;
  for (let i = 0; i < 200 && hi - lo > 1e-16; i++) {
    const mid = 0.5 * (lo + hi);
    if (f(mid) > 0) hi = mid; else lo = mid;
  }
  return cS * Math.sqrt(0.5 * (lo + hi));
}

/** {cL, cS, cR, sqrt2cS} for E, ν, ρ in plane strain (default) or plane stress. */
export function waveSpeeds(E, nu, rho, analysis = 'plane_strain') {
  const cS = Math.sqrt(E / (2 * (1 + nu) * rho));
  const cL = analysis === 'plane_stress'
    ? Math.sqrt(E / (rho * (1 - nu * nu)))
    : Math.sqrt((E * (1 - nu)) / (rho * (1 + nu) * (1 - 2 * nu)));
  return { cL, cS, cR: rayleighSpeed(cL, cS), sqrt2cS: Math.SQRT2 * cS };
}

function regionContains(region, [x, y]) {
  if (!region || typeof region !== 'object') return false;
  if (region.rectangle) {
    const { min, max } = region.rectangle;
    return x >= min[0] && x <= max[0] && y >= min[1] && y <= max[1];
  }
  if (region.circle) {
    const { center, radius } = region.circle;
    return (x - center[0]) ** 2 + (y - center[1]) ** 2 <= radius * radius;
  }
  if (region.polygon) {
    const p = region.polygon.points || [];
    let inside = false;
    for (let i = 0, j = p.length - 1; i < p.length; j = i++) {
      if ((p[i][1] > y) !== (p[j][1] > y)
        && x < ((p[j][0] - p[i][0]) * (y - p[i][1])) / (p[j][1] - p[i][1]) + p[i][0]) inside = !inside;
    }
    return inside;
  }
  return false;
}

/**
 * The material the cracks run in: that of the body containing a point of the first crack
 * (its first tip end that lies inside a body), else the first body's. Returns
 * {name, speeds, analysis} or null when the scene has no usable elastic material.
 */
export function sceneWaveSpeeds(scene) {
  if (!scene || !scene.materials || !Array.isArray(scene.bodies) || scene.bodies.length === 0) return null;
  let body = scene.bodies[0];
  const crack = (scene.cracks || [])[0];
  if (crack && Array.isArray(crack.points)) {
    const pts = crack.points;
    const candidates = [pts[0], pts[pts.length - 1]];
    if (pts.length >= 2) candidates.push([(pts[0][0] + pts[1][0]) / 2, (pts[0][1] + pts[1][1]) / 2]);
    outer: for (const pt of candidates) {
      for (const b of scene.bodies) if (regionContains(b.region, pt)) { body = b; break outer; }
    }
  }
  const m = scene.materials[body.material];
  if (!m || !(m.youngs_modulus > 0) || !(m.density > 0) || !(m.poissons_ratio > -1 && m.poissons_ratio < 0.5)) return null;
  const analysis = scene.analysis || 'plane_strain';
  return { name: body.material, analysis, speeds: waveSpeeds(m.youngs_modulus, m.poissons_ratio, m.density, analysis) };
}

/** Reference lines for a speed plot (labelled). */
export function speedRefLines(speeds, suffix = '') {
  if (!speeds) return [];
  return [
    { y: speeds.cR, label: `c_R${suffix}` },
    { y: speeds.cS, label: `c_S${suffix}` },
    { y: speeds.sqrt2cS, label: `√2·c_S${suffix}` },
    { y: speeds.cL, label: `c_L${suffix}` },
  ];
}
