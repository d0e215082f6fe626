//! The cohesive interface's bond law (`scene-format.md`, cohesive interfaces): one
//! traction–separation state per interface point, mixed-mode linear or exponential
//! softening, the work booked per bond. Dimension-free: the 2D solver's crack layer
//! (`fracture-solver`, crack/cohesive.rs) applies it along its interfaces.

use fracture_api::scene::{Cohesive, CohesiveLaw};

/// The cohesive state of one interface point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bond {
    /// The law's shape.
    pub law: CohesiveLaw,
    /// Peak tractions (Pa): opening, sliding.
    pub strength: [f64; 2],
    /// Characteristic separations δ_nc, δ_tc (m).
    pub critical: [f64; 2],
    /// Largest effective separation reached.
    pub lambda_max: f64,
    /// Effective separation at the last step (for the step's predicted interval).
    pub prev_lambda: f64,
    /// Work done by the traction so far (J, the scene's thickness).
    pub work: f64,
    /// Fully separated: the point is a crack point now.
    pub failed: bool,
    /// The force applied in the last step on the above side (N) and the separation then.
    pub last: Option<([f64; 2], [f64; 2])>,
    /// The rigid linear law: whether the bond has been loaded to its strength (a force stage
    /// whose impulse, capped at the strength, could not hold the fields). Until then the
    /// bond is rigid (`Cracks::bond_hold` ties the fields at the re-extrapolated stage too)
    /// and the little the surfaces' separation drifts is not an opening: counting it
    /// softened the whole bonded region of a double-cantilever beam ahead of its zone, whose
    /// points then carried nothing once closed and a huge secant stiffness once open, and the
    /// run blew up at cfl 0.25-0.5. Elastic laws (exponential, cubic) start engaged.
    pub engaged: bool,
    /// The separation (opening, sliding) the surfaces had when the bond engaged (m): the
    /// law's zero. Zero for the elastic laws.
    pub origin: [f64; 2],
    /// Length of interface this point holds (m), set each step.
    pub share: f64,
}

impl Bond {
    /// A fresh bond of `c`.
    pub fn new(c: &Cohesive) -> Bond {
        Bond {
            law: c.law,
            strength: [c.normal.strength, c.shear.strength],
            critical: [
                c.normal.critical_separation(c.law),
                c.shear.critical_separation(c.law),
            ],
            lambda_max: 0.0,
            prev_lambda: f64::NAN,
            work: 0.0,
            failed: false,
            last: None,
            engaged: !matches!(c.law, CohesiveLaw::Linear),
            origin: [0.0; 2],
            share: 0.0,
        }
    }

    /// In the process zone: past the peak traction and softened by more than 1 % of the
    /// strength (or failed). The margin keeps a rigid linear bond (peak at zero separation)
    /// whose surfaces drift by round-off under it out of the zone front (`Fronts::zone`).
    pub fn softening(&self) -> bool {
        self.failed
            || (self.lambda_max > self.law.peak()
                && self.law.shape(self.lambda_max) < 0.99 * self.law.shape(self.law.peak()))
    }

    /// T at λ for a largest separation `l_max` (no update).
    fn t_at(&self, l: f64, l_max: f64) -> f64 {
        let l_max = l_max.max(l);
        if l_max >= self.law.end() {
            return 0.0;
        }
        if l_max <= self.law.peak() || l >= l_max {
            // Elastic branch (reversible), or on the envelope.
            return self.law.shape(l);
        }
        // Damaged: the secant to the origin.
        self.law.shape(l_max) * l / l_max
    }

    /// The traction (opening σ ≥ 0, sliding τ with the sign of δ_t) over a step starting at
    /// separations (δ_n ≥ 0, δ_t): the law's mean over the interval the last step's rate
    /// predicts (midpoint rule on 8 parts, the damage following the path), so the step's work
    /// F·Δδ matches the law's area to second order. None while undamaged and rigid (the linear
    /// law at λ = 0): then the bond holds the fields together up to the strengths. Updates
    /// the damage; zero once failed.
    pub fn traction(&mut self, dn: f64, dt: f64) -> Option<[f64; 2]> {
        if !self.engaged {
            // Rigid until loaded to the strength: the drift so far is the law's zero.
            self.origin = [dn, dt];
            return None;
        }
        let dn = (dn - self.origin[0]).max(0.0);
        let dt = dt - self.origin[1];
        let a = [dn / self.critical[0], dt / self.critical[1]];
        let l = a[0].hypot(a[1]);
        let l_next = if self.prev_lambda.is_finite() {
            l + (l - self.prev_lambda)
        } else {
            l
        };
        self.prev_lambda = l;
        if l > self.lambda_max {
            self.lambda_max = l;
        }
        if self.lambda_max >= self.law.end() {
            self.failed = true;
        }
        if self.failed {
            return Some([0.0; 2]);
        }
        if l <= 0.0 {
            return match self.law {
                CohesiveLaw::Linear if self.lambda_max <= 0.0 => None,
                _ => Some([0.0; 2]),
            };
        }
        let t = if l_next > l {
            let n = 8;
            let (mut sum, mut l_max) = (0.0, self.lambda_max);
            for i in 0..n {
                let x = l + (l_next - l) * (f64::from(i) + 0.5) / f64::from(n);
                l_max = l_max.max(x);
                sum += self.t_at(x, l_max);
            }
            sum / f64::from(n)
        } else {
            self.t_at(l, self.lambda_max)
        };
        Some([
            self.strength[0] * t * a[0] / l,
            self.strength[1] * t * a[1] / l,
        ])
    }
}
