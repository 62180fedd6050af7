//! The orbit camera both viewports share: yaw and pitch around a target, a distance.

use glam::{Mat4, Vec2, Vec3};
use ragdoll_sim::scene::CameraDesc;

/// Vertical field of view (radians).
const FOV_Y: f32 = 45.0 * std::f32::consts::PI / 180.0;

/// Lowest pitch a drag can reach (radians, about 1°): the eye stays above its target,
/// which scenes place above the ground, so orbiting never takes the view under the
/// floor (where the ground would hide the bodies).
const MIN_PITCH: f32 = 0.02;
/// Highest pitch: just short of straight down, where the view's up vector degenerates.
const MAX_PITCH: f32 = 1.45;

/// Below this aspect ratio the vertical field of view widens (see `view_proj`).
const MIN_ASPECT: f32 = 4.0 / 3.0;

/// An orbit camera around `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at (m).
    pub target: Vec3,
    /// Rotation about world Y (radians); 0 looks along −Z.
    pub yaw: f32,
    /// Elevation above the horizon (radians), clamped short of the poles.
    pub pitch: f32,
    /// Distance from the target (m).
    pub distance: f32,
}

impl OrbitCamera {
    /// The camera a scene asks for.
    pub fn from_desc(desc: &CameraDesc) -> OrbitCamera {
        let offset = desc.eye - desc.target;
        let distance = offset.length().max(0.1);
        OrbitCamera {
            target: desc.target,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
            distance,
        }
    }

    /// Eye position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(sy * cp, sp, cy * cp)
    }

    /// World-to-clip matrix for a viewport of the given aspect ratio (width / height).
    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        let view = glam::camera::rh::view::look_at_mat4(self.eye(), self.target, Vec3::Y);
        let near = (self.distance * 0.01).clamp(0.01, 0.5);
        let aspect = aspect.max(1e-3);
        // A half of a split window is narrow: keep at least the horizontal field of view
        // of a 4:3 view, so a scene framed for the whole window still fits in each half.
        let fov = if aspect < MIN_ASPECT {
            2.0 * ((FOV_Y * 0.5).tan() * MIN_ASPECT / aspect).atan()
        } else {
            FOV_Y
        };
        let proj = glam::camera::rh::proj::directx::perspective(fov, aspect, near, 500.0);
        proj * view
    }

    /// Rotates by a mouse drag of `delta` pixels.
    pub fn orbit(&mut self, delta: Vec2) {
        self.yaw -= delta.x * 0.008;
        self.pitch = (self.pitch + delta.y * 0.008).clamp(MIN_PITCH.min(self.pitch), MAX_PITCH);
    }

    /// Moves the target in the view plane by a drag of `delta` pixels in a viewport
    /// `height` pixels tall, so the point under the cursor follows it.
    pub fn pan(&mut self, delta: Vec2, height: f32) {
        let forward = (self.target - self.eye()).normalize();
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        let up = right.cross(forward);
        let metres_per_pixel = 2.0 * self.distance * (FOV_Y * 0.5).tan() / height.max(1.0);
        self.target += (-delta.x * right + delta.y * up) * metres_per_pixel;
    }

    /// Zooms by `steps` wheel notches (positive: closer).
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.88f32.powf(steps)).clamp(0.2, 200.0);
    }

    /// Looks at `centre` from the same direction, from just far enough that a sphere of
    /// `radius` around it fills at most `fill` of the view's smaller field of view. The
    /// smaller half-angle is the vertical `FOV_Y / 2` in any viewport (`view_proj` only
    /// ever widens a field), and a sphere seen from distance `d` subtends `asin(r / d)`.
    pub fn fit(&mut self, centre: Vec3, radius: f32, fill: f32) {
        let half = (FOV_Y * 0.5) * fill.clamp(0.1, 1.0);
        self.target = centre;
        self.distance = (radius.max(0.01) / half.sin()).clamp(0.2, 200.0);
    }

    /// The world ray through a point of a viewport, `ndc` in [−1, 1]² (y up).
    pub fn ray(&self, ndc: Vec2, aspect: f32) -> (Vec3, Vec3) {
        let inv = self.view_proj(aspect).inverse();
        let near = inv.project_point3(ndc.extend(0.0));
        let far = inv.project_point3(ndc.extend(1.0));
        (near, (far - near).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn desc_round_trips_through_orbit_parameters() {
        let desc = CameraDesc {
            eye: Vec3::new(1.0, 2.0, 4.0),
            target: Vec3::new(0.0, 0.5, 0.0),
        };
        let cam = OrbitCamera::from_desc(&desc);
        assert!((cam.eye() - desc.eye).length() < 1e-5);
    }

    #[test]
    fn orbiting_never_takes_the_eye_under_its_target() {
        let mut cam = OrbitCamera::from_desc(&CameraDesc::default());
        for _ in 0..100 {
            cam.orbit(Vec2::new(3.0, -40.0));
        }
        assert!(cam.eye().y > cam.target.y, "eye {} under target", cam.eye());
        for _ in 0..100 {
            cam.orbit(Vec2::new(0.0, 40.0));
        }
        assert!(cam.pitch <= MAX_PITCH);
    }

    #[test]
    fn a_fitted_sphere_lies_inside_the_view_at_any_aspect() {
        let centre = Vec3::new(3.0, 1.0, -2.0);
        let radius = 2.5;
        for aspect in [0.6f32, 1.0, 1.36, 2.2] {
            let mut cam = OrbitCamera::from_desc(&CameraDesc::default());
            cam.fit(centre, radius, 0.8);
            let vp = cam.view_proj(aspect);
            // The sphere's extreme points along the view's axes and diagonals.
            let fwd = (cam.target - cam.eye()).normalize();
            let right = fwd.cross(Vec3::Y).normalize();
            let up = right.cross(fwd);
            for k in 0..16 {
                let a = k as f32 * std::f32::consts::TAU / 16.0;
                let p = centre + radius * (right * a.cos() + up * a.sin());
                let clip = vp * p.extend(1.0);
                let ndc = clip.truncate() / clip.w;
                assert!(
                    ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0,
                    "aspect {aspect}: {p} at {ndc}"
                );
            }
        }
    }

    #[test]
    fn centre_ray_hits_the_target() {
        let cam = OrbitCamera::from_desc(&CameraDesc::default());
        let (origin, dir) = cam.ray(Vec2::ZERO, 1.5);
        let to_target = cam.target - origin;
        // The target lies on the ray: its distance to the line is ~0.
        assert!(to_target.cross(dir).length() < 1e-3);
    }
}
