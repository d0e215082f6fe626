//! The process-zone law of a crack point created by growth (`algorithm.md` §7, "Energy"):
//! initially rigid linear softening from σ_c over δ_c = 2Γ/σ_c, unloading along the secant,
//! the work booked per point so each unit of new area takes Γ. Dimension-free: the 2D
//! solver's crack layer (`fracture-solver`, crack/zone.rs) applies it at its points.

/// Traction–separation state of one crack point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Zone {
    /// Peak traction σ_c (Pa).
    pub strength: f64,
    /// Toughness Γ the point takes per unit area (J/m²).
    pub toughness: f64,
    /// Separation at which linear softening reaches zero, δ_c = 2Γ/σ_c (m): where a point
    /// opened monotonically fails.
    pub critical_separation: f64,
    /// Largest effective separation reached (m).
    pub max_separation: f64,
    /// Energy the point's traction has removed from the body (J, the scene's thickness):
    /// Σ −F·Δδ, the force it applied in a step on the above side times the separation
    /// increment of that step (negative increments, faces closing against the traction,
    /// give energy back).
    pub work: f64,
    /// The largest `work` reached (J). Unloading along the secant gives energy back and
    /// reloading takes it again.
    pub positive_work: f64,
    /// Γ × the point's area at the last step (J): what it takes to fail it.
    pub capacity: f64,
    /// Which halves of its neighbouring segments the point carries: 0 both, +1 only the one
    /// towards the next point, −1 only the one towards the previous point (the scene's tip
    /// point, whose other half is the original, traction-free crack).
    pub side: i8,
    /// Force applied on the above side in the last step (N) and the separation then (m).
    pub last: Option<([f64; 2], [f64; 2])>,
    /// Effective separation at the last step (NaN before the first).
    pub prev_separation: f64,
    /// Failed in its tail: past δ_c, its faces stopped opening.
    pub dead: bool,
}

impl Zone {
    /// A fresh zone for toughness `gamma` (J/m²) and zone length `length` (m) in a medium of
    /// modulus `e_prime` (Pa).
    pub fn new(gamma: f64, length: f64, e_prime: f64) -> Zone {
        let strength = (std::f64::consts::PI * e_prime * gamma / (8.0 * length)).sqrt();
        Zone {
            strength,
            toughness: gamma,
            critical_separation: 2.0 * gamma / strength,
            max_separation: 0.0,
            work: 0.0,
            positive_work: 0.0,
            capacity: 0.0,
            side: 0,
            last: None,
            prev_separation: f64::NAN,
            dead: false,
        }
    }

    /// Whether the point carries no traction any more: opened past δ_c, or has taken its
    /// toughness × area.
    pub fn failed(&self) -> bool {
        self.dead
            || self.max_separation >= Self::TAIL * self.critical_separation
            || (self.capacity > 0.0 && self.positive_work >= self.capacity)
    }

    /// A point opened past δ_c that has taken less than Γ × area (the explicit step and the
    /// stick limit of its impulses lose a few per cent) keeps the tail traction
    /// σ_c·sqrt(1 − W/(Γ·area)) (which reaches zero at a finite opening) until it has, or
    /// until it opens past this many δ_c.
    pub const TAIL: f64 = 3.0;

    /// Damage D ∈ [0, 1]: the fraction of Γ·area taken so far.
    pub fn damage(&self) -> f64 {
        if self.capacity > 0.0 {
            (self.positive_work / self.capacity).min(1.0)
        } else {
            0.0
        }
    }

    /// Book a work increment (J) of the point's traction.
    pub fn book(&mut self, w: f64) {
        self.work += w;
        self.positive_work = self.positive_work.max(self.work);
    }

    /// The law at separation `x` for a largest separation `s_max` (no update): linear
    /// softening σ_c(1 − s_max/δ_c), the secant to the origin below s_max.
    pub fn law(&self, x: f64, s_max: f64) -> f64 {
        let s_max = s_max.max(x);
        let d = s_max / self.critical_separation;
        if d >= 1.0 {
            return 0.0;
        }
        let peak = self.strength * (1.0 - d);
        if x >= s_max || s_max <= 0.0 {
            peak
        } else {
            peak * x / s_max
        }
    }

    /// The traction to apply over a step that starts at separation `s` and is expected to
    /// end near `s_next` (the last step's rate carried on): the law's mean over the interval
    /// (midpoint rule on 8 parts, the damage following the path), so that the step's work
    /// F·Δδ matches the law's area to second order instead of lagging it by a step. Updates
    /// the damage with `s`; zero once the point has failed, by opening past δ_c or by having
    /// taken Γ × its area (the second caps the explicit step's residual lag).
    pub fn traction(&mut self, s: f64, s_next: f64) -> f64 {
        if s > self.max_separation {
            self.max_separation = s;
        }
        if self.failed() {
            return 0.0;
        }
        if self.max_separation >= self.critical_separation {
            // Past the law's end: the tail that takes the rest of Γ × area while the faces
            // keep opening. Faces that stop opening end it: a traction that does not follow
            // the separation would pump energy into faces vibrating under it (seen on a strip
            // at 0.5 mm cells: −17.9 J "dissipated").
            if s < self.max_separation {
                self.dead = true;
                return 0.0;
            }
            return if self.capacity > 0.0 {
                self.strength * (1.0 - self.positive_work / self.capacity).max(0.0).sqrt()
            } else {
                0.0
            };
        }
        if s_next.is_nan() || s_next <= s {
            return self.law(s, self.max_separation);
        }
        let n = 8;
        let (mut sum, mut s_max) = (0.0, self.max_separation);
        for i in 0..n {
            let x = s + (s_next - s) * (f64::from(i) + 0.5) / f64::from(n);
            s_max = s_max.max(x);
            sum += self.law(x, s_max);
        }
        sum / f64::from(n)
    }
}

#[cfg(test)]
mod tests {
    use super::Zone;

    /// A point opened monotonically in small steps, each step's work booked as the traction
    /// at its start times the increment (as the solver does): it fails having taken Γ·area
    /// (to the last step's increment), at the separation δ_c = 2Γ/σ_c of linear softening;
    /// closing half-way and reopening adds no energy.
    #[test]
    fn law_takes_its_toughness_and_fails_at_the_critical_opening() {
        for (gamma, len, e) in [(25.0, 2e-3, 5.9e9), (250.0, 5e-4, 2.1e11)] {
            let mut z = Zone::new(gamma, len, e);
            z.capacity = gamma * 1e-3; // 1 mm × 1 m
            let dc = z.critical_separation;
            let ds = dc / 2000.0;
            let mut s = 0.0;
            let mut path = Vec::new();
            while s < 0.5 * dc {
                s += ds;
                path.push(s);
            }
            while s > 0.25 * dc {
                s -= ds;
                path.push(s);
            }
            while s < 2.0 * dc {
                s += ds;
                path.push(s);
            }
            let (mut s0, mut fail_at) = (0.0, f64::NAN);
            let mut sigma = z.traction(0.0, ds);
            for &x in &path {
                z.book(sigma * 1e-3 * (x - s0));
                if z.failed() && fail_at.is_nan() {
                    fail_at = x;
                }
                sigma = z.traction(x, x + (x - s0));
                s0 = x;
            }
            assert!(z.failed());
            assert!(
                (z.work / z.capacity - 1.0).abs() < 2e-3,
                "work/capacity {}",
                z.work / z.capacity
            );
            assert!(
                (0.98..1.1).contains(&(fail_at / dc)),
                "failed at {fail_at} vs δ_c {dc}"
            );
        }
    }
}
