//! Rays through the cursor and framing: which half a pixel lies in, the world ray through
//! it (for picking, grabbing and shooting), and the camera that fits a set of bodies.
//!
//! Both halves show the same world through the same camera, so a pixel of either half
//! gives the same ray in its own viewport coordinates: a shot or a pick through the right
//! half goes where the cursor points there, and hits the same place in the left world.

use crate::render::Viewport;
use crate::render::camera::OrbitCamera;
use glam::{Vec2, Vec3};
use ragdoll_sim::scene::{BodyId, SceneDesc};
use ragdoll_sim::snapshot::RenderSnapshot;

/// A world ray through a cursor pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CursorRay {
    /// The half the pixel lies in: 0 particle (left), 1 multibody (right).
    pub side: usize,
    /// Ray origin on the near plane (m).
    pub origin: Vec3,
    /// Unit direction.
    pub dir: Vec3,
}

/// The ray through pixel `p` (physical pixels) of whichever half contains it, or `None`
/// over neither (the panel).
pub fn cursor_ray(camera: &OrbitCamera, viewports: &[Viewport; 2], p: Vec2) -> Option<CursorRay> {
    let side = viewports.iter().position(|vp| vp.contains(p))?;
    let vp = viewports[side];
    let (origin, dir) = camera.ray(vp.ndc(p), vp.aspect());
    Some(CursorRay { side, origin, dir })
}

/// The ray through the centre of the left half (the panel's Shoot button).
pub fn centre_ray(camera: &OrbitCamera, viewports: &[Viewport; 2]) -> CursorRay {
    let vp = viewports[0];
    let (origin, dir) = camera.ray(Vec2::ZERO, vp.aspect());
    CursorRay {
        side: 0,
        origin,
        dir,
    }
}

/// A sphere around the bodies of `snapshots` (each body's centre plus its bounding
/// radius), or only those whose index `keep` accepts. `None` if no body is kept.
pub fn bounding_sphere(
    snapshots: &[RenderSnapshot],
    keep: impl Fn(usize) -> bool,
) -> Option<(Vec3, f32)> {
    let bodies = || {
        snapshots
            .iter()
            .flat_map(|s| &s.bodies)
            .filter(|b| keep(b.body.index()))
    };
    let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for b in bodies() {
        let r = b.shape.local_half_extents().length();
        min = min.min(b.pose.position - Vec3::splat(r));
        max = max.max(b.pose.position + Vec3::splat(r));
    }
    if !min.is_finite() || !max.is_finite() {
        return None;
    }
    let centre = (min + max) * 0.5;
    let radius = bodies()
        .map(|b| b.pose.position.distance(centre) + b.shape.local_half_extents().length())
        .fold(0.0f32, f32::max);
    Some((centre, radius.max(0.05)))
}

/// The bodies of the figure `selected` belongs to (every body its joints connect it to,
/// transitively), or every dynamic body without a selection: what F follows.
pub fn figure(desc: &SceneDesc, selected: Option<BodyId>) -> Box<dyn Fn(usize) -> bool> {
    let n = desc.bodies.len();
    let mut member = vec![false; n];
    match selected {
        Some(b) if b.index() < n => {
            member[b.index()] = true;
            // Grow along joints until nothing new joins (n rounds at most).
            loop {
                let mut grew = false;
                for c in &desc.constraints {
                    if let Some(b2) = c.body2.body() {
                        let (i, j) = (c.body1.index(), b2.index());
                        if i < n && j < n && member[i] != member[j] {
                            member[i] = true;
                            member[j] = true;
                            grew = true;
                        }
                    }
                }
                if !grew {
                    break;
                }
            }
            member
                .iter_mut()
                .zip(&desc.bodies)
                .for_each(|(m, b)| *m &= !b.is_fixed());
            member[b.index()] = true;
            Box::new(move |i| member.get(i).copied().unwrap_or(false))
        }
        // Projectiles (indices past the scene's bodies) count as part of the scene.
        _ => {
            let fixed: Vec<bool> = desc.bodies.iter().map(|b| b.is_fixed()).collect();
            Box::new(move |i| !fixed.get(i).copied().unwrap_or(false))
        }
    }
}

/// Moves `camera` a step towards framing the sphere: the target follows the centre and
/// the distance the fit, each closing ~90 % of the way per second (`1 − e^(−2.3 dt)`),
/// so the view glides instead of jumping with every bounce.
pub fn follow(camera: &mut OrbitCamera, centre: Vec3, radius: f32, dt: f32) {
    let mut goal = *camera;
    goal.fit(centre, radius, FILL);
    let k = 1.0 - (-2.3 * dt.max(0.0)).exp();
    camera.target += (goal.target - camera.target) * k;
    camera.distance += (goal.distance - camera.distance) * k;
}

/// How much of the view a fitted sphere fills (of the smaller field of view).
const FILL: f32 = 0.85;

/// Whether every body of `snapshots` lies inside a view of `aspect` seen by `camera`,
/// clear of the labels: each body's bounding box corners project inside x ∈ [−0.95, 0.95]
/// and y ∈ [−0.85, 0.75] of the view (the top band holds the method labels, the bottom
/// one the clock).
pub fn fits(camera: &OrbitCamera, snapshots: &[RenderSnapshot], aspect: f32) -> bool {
    let vp = camera.view_proj(aspect);
    snapshots.iter().flat_map(|s| &s.bodies).all(|b| {
        let h = b.shape.local_half_extents();
        (0..8).all(|k| {
            let corner = Vec3::new(
                if k & 1 == 0 { -h.x } else { h.x },
                if k & 2 == 0 { -h.y } else { h.y },
                if k & 4 == 0 { -h.z } else { h.z },
            );
            let p = b.pose.position + b.pose.rotation * corner;
            let clip = vp * p.extend(1.0);
            if clip.w <= 1e-4 {
                return false;
            }
            let ndc = clip.truncate() / clip.w;
            ndc.x.abs() <= 0.95 && (-0.85..=0.75).contains(&ndc.y)
        })
    })
}

/// `camera` (a scene's own), or, if the bodies do not all fit in it (see [`fits`]), the
/// camera looking from the same direction at the sphere around them, from far enough.
pub fn scene_camera(camera: OrbitCamera, snapshots: &[RenderSnapshot], aspect: f32) -> OrbitCamera {
    if fits(&camera, snapshots, aspect) {
        return camera;
    }
    let Some((centre, radius)) = bounding_sphere(snapshots, |_| true) else {
        return camera;
    };
    let mut fitted = camera;
    fitted.fit(centre, radius, FILL);
    // Far enough that the corners clear the bands too; a sphere fit is generous already,
    // but a tall figure in a narrow half may need more.
    for _ in 0..20 {
        if fits(&fitted, snapshots, aspect) {
            break;
        }
        fitted.distance *= 1.1;
    }
    fitted
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::split;
    use ragdoll_sim::scene::CameraDesc;

    fn halves() -> [Viewport; 2] {
        split(Viewport {
            x: 300.0,
            y: 0.0,
            width: 980.0,
            height: 720.0,
        })
    }

    fn camera() -> OrbitCamera {
        OrbitCamera::from_desc(&CameraDesc {
            eye: Vec3::new(1.0, 2.0, 5.0),
            target: Vec3::new(0.0, 0.8, 0.0),
        })
    }

    /// Distance from `p` to the line through `o` along unit `d`.
    fn off_ray(p: Vec3, o: Vec3, d: Vec3) -> f32 {
        (p - o).cross(d).length()
    }

    #[test]
    fn the_ray_through_a_points_pixel_passes_through_the_point_in_both_halves() {
        let (cam, vps) = (camera(), halves());
        for world in [
            Vec3::new(0.0, 0.8, 0.0),
            Vec3::new(0.7, 0.1, -0.4),
            Vec3::new(-1.2, 1.9, 0.9),
        ] {
            for (side, vp) in vps.iter().enumerate() {
                let pixel = vp.project(&cam, world).expect("in front");
                let ray = cursor_ray(&cam, &vps, pixel).expect("inside a half");
                assert_eq!(ray.side, side, "{pixel} lies in half {side}");
                assert!((ray.dir.length() - 1.0).abs() < 1e-5);
                let miss = off_ray(world, ray.origin, ray.dir);
                assert!(
                    miss < 2e-3,
                    "half {side}: the ray passes {miss} m from {world}"
                );
                assert!(ray.dir.dot(world - ray.origin) > 0.0, "ahead, not behind");
            }
        }
    }

    #[test]
    fn no_ray_over_the_panel_and_the_centre_ray_hits_the_target() {
        let (cam, vps) = (camera(), halves());
        assert_eq!(cursor_ray(&cam, &vps, Vec2::new(100.0, 300.0)), None);
        let c = centre_ray(&cam, &vps);
        assert!(off_ray(cam.target, c.origin, c.dir) < 1e-3);
    }

    #[test]
    fn a_sphere_holds_every_kept_body() {
        use ragdoll_sim::scene::{BodyId, Pose, Shape};
        use ragdoll_sim::snapshot::{BodyInstance, BodyRole};
        let body = |i: u32, x: f32| BodyInstance {
            body: BodyId(i),
            shape: Shape::Box {
                half_extents: Vec3::splat(0.1),
            },
            pose: Pose {
                position: Vec3::new(x, 1.0, 0.0),
                rotation: glam::Quat::IDENTITY,
            },
            role: BodyRole::Dynamic,
        };
        let snap = RenderSnapshot {
            bodies: vec![body(0, -1.0), body(1, 2.0), body(2, 50.0)],
            ..Default::default()
        };
        let (c, r) = bounding_sphere(&[snap], |i| i < 2).unwrap();
        let corner = 0.1 * 3f32.sqrt();
        assert!((c.x - 0.5).abs() < 1e-5, "{c}");
        assert!((r - (1.5 + corner)).abs() < 1e-4, "{r}");
        assert!(bounding_sphere(&[RenderSnapshot::default()], |_| true).is_none());
    }

    #[test]
    fn a_figure_is_what_its_joints_connect_and_following_closes_in_on_it() {
        use ragdoll_sim::scene::{
            BodyDesc, BodyRef, ConstraintDesc, JointKind, MassSpec, Motion, Pose, Shape,
        };
        let body = |name: &str| {
            BodyDesc::new(
                name.to_string(),
                Shape::Box {
                    half_extents: Vec3::splat(0.1),
                },
                Pose::default(),
                MassSpec::Mass(1.0),
            )
        };
        let joint = |a: u32, b: u32| ConstraintDesc {
            name: format!("{a}-{b}"),
            body1: BodyId(a),
            body2: BodyRef::Body(BodyId(b)),
            kind: JointKind::BallAndSocket {
                anchor: Vec3::ZERO,
                swing: None,
                twist: None,
                limit_style: Default::default(),
            },
            friction: 0.0,
        };
        // Two figures, 0-1-2 and 3-4, and a fixed body 5 that 2 hangs from.
        let mut bodies: Vec<BodyDesc> = ["a", "b", "c", "d", "e", "post"]
            .iter()
            .map(|n| body(n))
            .collect();
        bodies[5].motion = Motion::Fixed;
        let desc = SceneDesc {
            bodies,
            constraints: vec![joint(1, 0), joint(2, 1), joint(3, 4), joint(2, 5)],
            ..Default::default()
        };
        let of = |sel: Option<u32>| {
            let f = figure(&desc, sel.map(BodyId));
            (0..7).filter(|&i| f(i)).collect::<Vec<_>>()
        };
        assert_eq!(of(Some(0)), [0, 1, 2], "through joints, not the fixed post");
        assert_eq!(of(Some(4)), [3, 4]);
        assert_eq!(
            of(None),
            [0, 1, 2, 3, 4, 6],
            "every dynamic body and projectiles"
        );

        let mut cam = camera();
        let (centre, radius) = (Vec3::new(5.0, 1.0, -3.0), 1.0);
        let mut goal = cam;
        goal.fit(centre, radius, FILL);
        for _ in 0..120 {
            follow(&mut cam, centre, radius, 1.0 / 60.0);
        }
        // Two seconds close 1 − e^(−4.6) ≈ 99 % of the way.
        assert!(cam.target.distance(centre) < 0.02 * centre.distance(camera().target));
        assert!((cam.distance - goal.distance).abs() < 0.02 * goal.distance.max(1.0));
    }
}
