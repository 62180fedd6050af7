//! Colours: the particle method in blues (left), the multibody method in reds (right).
//!
//! Values are sRGB; [`linear`] converts them for the shader, which writes to an sRGB target.

use ragdoll_sim::MethodKind;
use ragdoll_sim::snapshot::{BodyRole, ParticleRole, StickRole};

/// sRGB to linear, per channel.
pub fn linear(c: [f32; 3]) -> [f32; 4] {
    let f = |u: f32| {
        if u <= 0.04045 {
            u / 12.92
        } else {
            ((u + 0.055) / 1.055).powf(2.4)
        }
    };
    [f(c[0]), f(c[1]), f(c[2]), 1.0]
}

/// Four shades per side, cycled over bodies so neighbouring bones are told apart.
const BLUES: [[f32; 3]; 4] = [
    [0.20, 0.42, 0.88],
    [0.14, 0.32, 0.74],
    [0.30, 0.55, 0.96],
    [0.18, 0.47, 0.80],
];
const REDS: [[f32; 3]; 4] = [
    [0.88, 0.20, 0.16],
    [0.74, 0.13, 0.12],
    [0.96, 0.34, 0.26],
    [0.82, 0.24, 0.20],
];

/// Colour of body number `index` of a method's snapshot.
pub fn body(kind: MethodKind, role: BodyRole, index: usize) -> [f32; 4] {
    let blue = kind == MethodKind::Particle;
    let c = match role {
        BodyRole::Dynamic => {
            if blue {
                BLUES[index % 4]
            } else {
                REDS[index % 4]
            }
        }
        BodyRole::Asleep => {
            let c = if blue {
                BLUES[index % 4]
            } else {
                REDS[index % 4]
            };
            [c[0] * 0.6, c[1] * 0.6, c[2] * 0.6]
        }
        BodyRole::Fixed => {
            if blue {
                [0.22, 0.30, 0.58]
            } else {
                [0.58, 0.26, 0.22]
            }
        }
        BodyRole::Grabbed => {
            if blue {
                [0.55, 0.78, 1.00]
            } else {
                [1.00, 0.62, 0.52]
            }
        }
        BodyRole::Projectile => {
            if blue {
                [0.16, 0.66, 0.84]
            } else {
                [0.94, 0.52, 0.16]
            }
        }
    };
    linear(c)
}

/// The paper's particle colours (figure 31): green at joints, red inside a bone.
pub fn particle(role: ParticleRole) -> [f32; 4] {
    linear(match role {
        ParticleRole::Joint => [0.20, 0.85, 0.30],
        ParticleRole::Internal => [0.92, 0.22, 0.22],
        ParticleRole::Fixed => [0.55, 0.55, 0.55],
    })
}

/// Stick colours.
pub fn stick(role: StickRole) -> [f32; 4] {
    linear(match role {
        StickRole::Bone => [0.95, 0.95, 0.95],
        StickRole::Joint => [1.00, 0.85, 0.20],
        StickRole::Limit => [0.95, 0.30, 0.95],
    })
}

/// Contact points and normals.
pub const CONTACT: [f32; 3] = [1.0, 0.9, 0.1];
/// Joint limit cones and arcs.
pub const LIMIT: [f32; 3] = [0.2, 0.95, 0.9];
/// Clear colour behind the ground (sRGB).
pub const SKY: [f32; 3] = [0.80, 0.82, 0.84];
