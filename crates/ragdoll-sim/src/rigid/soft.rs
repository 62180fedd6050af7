//! Soft constraints (Catto, "Solver2D", 2024; Box2D v3 `b2Softness`).
//!
//! A constraint with position error `C` is treated as a damped spring of natural
//! frequency ω = 2π·hertz and damping ratio ζ, integrated implicitly over the substep h.
//! With `a₁ = 2ζ + hω`, `a₂ = hω a₁`, `a₃ = 1/(1 + a₂)` the velocity update becomes
//!
//! `λ = −m_eff · mass_scale · (Ċ + bias_rate · C) − impulse_scale · λ_acc`
//!
//! with `bias_rate = ω / a₁`, `mass_scale = a₂ a₃`, `impulse_scale = a₃`. A rigid
//! constraint is the limit ω → ∞; the softness is what keeps stiff stacks and large mass
//! ratios stable at a few substeps.

/// Coefficients of one soft constraint for a given substep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Softness {
    /// Fraction of the position error fed back per second (1/s).
    pub bias_rate: f32,
    /// Scale on the effective mass.
    pub mass_scale: f32,
    /// Scale on the accumulated impulse (the spring's "memory").
    pub impulse_scale: f32,
}

impl Softness {
    /// A rigid constraint without position feedback (the relax and restitution passes).
    pub const RIGID: Softness = Softness {
        bias_rate: 0.0,
        mass_scale: 1.0,
        impulse_scale: 0.0,
    };

    /// Soft coefficients for `hertz` and damping ratio `zeta` at substep `h`.
    pub fn new(hertz: f32, zeta: f32, h: f32) -> Softness {
        if hertz <= 0.0 {
            return Softness {
                bias_rate: 0.0,
                mass_scale: 1.0,
                impulse_scale: 0.0,
            };
        }
        let omega = 2.0 * std::f32::consts::PI * hertz;
        let a1 = 2.0 * zeta + h * omega;
        let a2 = h * omega * a1;
        let a3 = 1.0 / (1.0 + a2);
        Softness {
            bias_rate: omega / a1,
            mass_scale: a2 * a3,
            impulse_scale: a3,
        }
    }
}

/// An implicit spring-damper of stiffness `k` and damping `c` on one constraint row, in
/// the Gauss–Seidel form of Box2D's soft distance joint:
/// `γ = 1/(h(c + hk))`, `bias = k C / (c + hk)`, `λ = −(Ċ + bias + γ λ_acc)/(1/m_eff + γ)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spring {
    /// `γ`, the compliance per substep.
    pub gamma: f32,
    /// `k / (c + hk)`: velocity bias per unit of error.
    pub bias_rate: f32,
}

impl Spring {
    /// Coefficients for stiffness `k` and damping `c` at substep `h`; `None` when both are
    /// zero (no force at all).
    pub fn new(k: f32, c: f32, h: f32) -> Option<Spring> {
        let d = c + h * k;
        if d <= 0.0 {
            return None;
        }
        Some(Spring {
            gamma: 1.0 / (h * d),
            bias_rate: k / d,
        })
    }
}

/// Per-substep solver parameters shared by all constraints.
#[derive(Clone, Copy, Debug)]
pub struct StepContext {
    /// Substep length (s).
    pub h: f32,
    /// 1 / h.
    pub inv_h: f32,
    /// Softness of joints.
    pub joint: Softness,
    /// Softness of contacts.
    pub contact: Softness,
    /// Largest speed at which penetration is resolved (m/s).
    pub max_push_out: f32,
}
