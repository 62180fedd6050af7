//! The metrics of DESIGN.md ("Metrics"), accumulated over a run of [`Sample`]s.
//!
//! Methods report instantaneous values ([`Sample`]); this module owns the definitions
//! that span time (energy gain against the running minimum, maxima, first sleep) and the
//! energy scale, so both methods are measured by the same code.

use crate::method::{BodyState, Sample};
use crate::scene::{SceneDesc, SceneError, Settings, scene_mass_props};
use glam::Vec3;

/// Potential energy that is there to lose (J):
/// `g · Σ m · max(h₀ − h_rest, 0.1 m)` over dynamic bodies, where h₀ is the initial
/// centre-of-mass height above the ground and h_rest the body's smallest half extent.
pub fn energy_scale_j(scene: &SceneDesc) -> Result<f64, SceneError> {
    let props = scene_mass_props(scene)?;
    let g = scene.settings.gravity.length() as f64;
    let mut total = 0.0;
    for (body, mp) in scene.bodies.iter().zip(&props) {
        if body.is_fixed() {
            continue;
        }
        let com = body.pose.transform_point(mp.local_com);
        let h0 = height_above_ground(scene, com) as f64;
        let h_rest = body.shape.local_half_extents().min_element() as f64;
        total += mp.mass as f64 * (h0 - h_rest).max(0.1);
    }
    Ok(g * total)
}

/// Height of a point above the ground plane along gravity's opposite (or above y = 0
/// when the scene has no ground).
pub fn height_above_ground(scene: &SceneDesc, p: Vec3) -> f32 {
    match &scene.settings.ground {
        Some(g) => g.height_of(p),
        None => p.y,
    }
}

/// Gravitational potential of mass `m` at point `p` (J), zero on the ground plane.
pub fn potential_energy(settings: &Settings, m: f32, p: Vec3) -> f64 {
    let g = settings.gravity;
    // m g h with h along -g: for gravity (0, -9.81, 0) and a flat ground this is m·9.81·y.
    let up = -g.normalize_or_zero();
    let base = match &settings.ground {
        Some(gr) => Vec3::new(0.0, gr.height, 0.0),
        None => Vec3::ZERO,
    };
    m as f64 * g.length() as f64 * up.dot(p - base) as f64
}

/// The per-method summary printed by `ragdoll-lab stats`.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodStats {
    /// `energy_scale_j` (J).
    pub energy_scale_j: f64,
    /// Largest rise of E above its running minimum, over the energy scale.
    pub energy_gain: f64,
    /// Largest fall of E below its value at the start, over the energy scale:
    /// `max_t (E(0) − E(t)) / scale`. Meaningful where nothing dissipates (no air or
    /// joint friction, no contact that slides or stops a fall); there it is energy the
    /// solver took away, which `energy_gain` does not see.
    pub energy_loss: f64,
    /// Largest linear speed of any body's centre of mass over the run (m/s), from
    /// [`MetricsRecorder::record_speeds`].
    pub max_body_speed_mps: f32,
    /// Kinetic energy at the end, over the energy scale.
    pub final_kinetic: f64,
    /// Deepest penetration over the run (m).
    pub max_penetration_m: f32,
    /// Largest joint gap over the run (m).
    pub max_joint_gap_m: f32,
    /// Largest limit violation over the run (degrees).
    pub max_limit_violation_deg: f32,
    /// Largest relative bone stretch (particle method).
    pub max_bone_stretch: Option<f32>,
    /// First time every body was asleep (s).
    pub asleep_at_s: Option<f64>,
    /// Every sample was finite.
    pub finite: bool,
    /// Number of samples recorded.
    pub frames: usize,
}

/// The largest rise of an energy above its running minimum so far,
/// `max_t (E(t) − min_{s≤t} E(s))` (J): energy may leave a closed scene, never enter it.
#[derive(Clone, Copy, Debug)]
pub struct EnergyRise {
    running_min: f64,
    rise: f64,
}

impl Default for EnergyRise {
    fn default() -> Self {
        EnergyRise {
            running_min: f64::INFINITY,
            rise: 0.0,
        }
    }
}

impl EnergyRise {
    /// Records the energy `e` (J) at the next time.
    pub fn record(&mut self, e: f64) {
        self.running_min = self.running_min.min(e);
        self.rise = self.rise.max(e - self.running_min);
    }

    /// The largest rise so far (J).
    pub fn rise(&self) -> f64 {
        self.rise
    }
}

/// Accumulates samples into [`MethodStats`].
#[derive(Clone, Debug)]
pub struct MetricsRecorder {
    scale: f64,
    gain: EnergyRise,
    start_energy: Option<f64>,
    loss: f64,
    max_speed: f32,
    last_kinetic: f64,
    max_pen: f32,
    max_gap: f32,
    max_limit: f32,
    max_stretch: Option<f32>,
    asleep_at: Option<f64>,
    finite: bool,
    frames: usize,
}

impl MetricsRecorder {
    /// A recorder for a scene; the energy scale comes from the scene's initial state.
    pub fn new(scene: &SceneDesc) -> Result<Self, SceneError> {
        Ok(MetricsRecorder {
            scale: energy_scale_j(scene)?,
            gain: EnergyRise::default(),
            start_energy: None,
            loss: 0.0,
            max_speed: 0.0,
            last_kinetic: 0.0,
            max_pen: 0.0,
            max_gap: 0.0,
            max_limit: 0.0,
            max_stretch: None,
            asleep_at: None,
            finite: true,
            frames: 0,
        })
    }

    /// Records the sample taken at simulated time `t` (s).
    pub fn record(&mut self, t: f64, s: &Sample) {
        self.frames += 1;
        let values_finite = s.energy.is_finite()
            && s.kinetic.is_finite()
            && s.max_penetration.is_finite()
            && s.max_joint_gap.is_finite()
            && s.max_limit_violation_deg.is_finite()
            && s.max_bone_stretch.is_none_or(f32::is_finite);
        if !values_finite {
            self.finite = false;
            return;
        }
        // energy_gain = max_t (E(t) - min_{s<=t} E(s)) / scale
        self.gain.record(s.energy);
        // energy_loss = max_t (E(0) - E(t)) / scale, E(0) the first sample's energy.
        let start = *self.start_energy.get_or_insert(s.energy);
        self.loss = self.loss.max(start - s.energy);
        self.last_kinetic = s.kinetic;
        self.max_pen = self.max_pen.max(s.max_penetration);
        self.max_gap = self.max_gap.max(s.max_joint_gap);
        self.max_limit = self.max_limit.max(s.max_limit_violation_deg);
        if let Some(st) = s.max_bone_stretch {
            self.max_stretch = Some(self.max_stretch.unwrap_or(0.0).max(st));
        }
        if s.all_asleep && self.asleep_at.is_none() {
            self.asleep_at = Some(t);
        }
    }

    /// Records the bodies' states at the time of the last sample: the largest
    /// centre-of-mass speed. A non-finite speed marks the run not finite.
    pub fn record_speeds(&mut self, states: &[BodyState]) {
        for b in states {
            let v = b.linear_velocity.length();
            if !v.is_finite() {
                self.finite = false;
                return;
            }
            self.max_speed = self.max_speed.max(v);
        }
    }

    /// The summary so far.
    pub fn stats(&self) -> MethodStats {
        MethodStats {
            energy_scale_j: self.scale,
            energy_gain: self.gain.rise() / self.scale,
            energy_loss: self.loss / self.scale,
            max_body_speed_mps: self.max_speed,
            final_kinetic: self.last_kinetic / self.scale,
            max_penetration_m: self.max_pen,
            max_joint_gap_m: self.max_gap,
            max_limit_violation_deg: self.max_limit,
            max_bone_stretch: self.max_stretch,
            asleep_at_s: self.asleep_at,
            finite: self.finite,
            frames: self.frames,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(e: f64) -> Sample {
        Sample {
            energy: e,
            kinetic: 0.0,
            ..Default::default()
        }
    }

    #[test]
    fn gain_is_rise_above_running_minimum() {
        let scene = SceneDesc::default();
        let mut r = MetricsRecorder::new(&scene).unwrap();
        r.scale = 10.0;
        for e in [5.0, 3.0, 4.0, 1.0, 1.5, 0.5] {
            r.record(0.0, &sample(e));
        }
        // Largest rise: 3 -> 4 = 1.0 (1 -> 1.5 is only 0.5).
        assert!((r.stats().energy_gain - 0.1).abs() < 1e-12);
    }

    #[test]
    fn loss_is_largest_fall_below_the_start() {
        let scene = SceneDesc::default();
        let mut r = MetricsRecorder::new(&scene).unwrap();
        r.scale = 10.0;
        for e in [5.0, 6.0, 3.0, 4.0, 4.5] {
            r.record(0.0, &sample(e));
        }
        // Start 5, lowest 3: a fall of 2 (the rise to 6 is not a loss).
        assert!((r.stats().energy_loss - 0.2).abs() < 1e-12);
    }

    #[test]
    fn largest_body_speed_is_kept() {
        let scene = SceneDesc::default();
        let mut r = MetricsRecorder::new(&scene).unwrap();
        let at = |v: Vec3| BodyState {
            com: Vec3::ZERO,
            orientation: glam::Quat::IDENTITY,
            linear_velocity: v,
            angular_velocity: Vec3::ZERO,
        };
        r.record_speeds(&[at(Vec3::new(3.0, 4.0, 0.0)), at(Vec3::X)]);
        r.record_speeds(&[at(Vec3::Y)]);
        assert_eq!(r.stats().max_body_speed_mps, 5.0);
        r.record_speeds(&[at(Vec3::splat(f32::NAN))]);
        assert!(!r.stats().finite);
    }

    #[test]
    fn nan_marks_run_not_finite() {
        let scene = SceneDesc::default();
        let mut r = MetricsRecorder::new(&scene).unwrap();
        r.record(0.0, &sample(f64::NAN));
        assert!(!r.stats().finite);
    }
}
