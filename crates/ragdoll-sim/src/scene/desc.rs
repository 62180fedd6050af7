//! `SceneDesc`: the plain-data description both methods are built from.
//!
//! Everything here is settings, not instance: no method state, no caches. A method
//! reads a `SceneDesc` once and builds its own runtime arrays from it. All values are
//! SI (metres, kilograms, seconds, radians) in a right-handed frame with **Y up**;
//! the `.af` reader converts Doom 3's inches and Z-up on the way in.
//!
//! World-space conventions: every anchor, axis and pose below is given in world space
//! *at the rest pose* (the pose the scene starts in), exactly as Doom 3 `.af` files give
//! them. A method that needs body-local quantities transforms them by the inverse of the
//! body's initial pose.

use glam::{Quat, Vec3};
use std::sync::Arc;

/// Index of a body in [`SceneDesc::bodies`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(pub u32);

impl BodyId {
    /// The index as `usize`, for addressing `SceneDesc::bodies`.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A rigid transform: rotation then translation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// World position of the frame origin (metres).
    pub position: Vec3,
    /// World orientation of the frame (unit quaternion).
    pub rotation: Quat,
}

impl Pose {
    /// The identity pose.
    pub const IDENTITY: Pose = Pose {
        position: Vec3::ZERO,
        rotation: Quat::IDENTITY,
    };

    /// A pose with the given position and no rotation.
    pub fn from_position(position: Vec3) -> Pose {
        Pose {
            position,
            rotation: Quat::IDENTITY,
        }
    }

    /// Maps a point from this frame to the parent (world) frame.
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.position + self.rotation * p
    }

    /// Maps a point from the parent (world) frame into this frame.
    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.inverse() * (p - self.position)
    }

    /// Maps a direction from this frame to the parent frame.
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    /// Maps a direction from the parent frame into this frame.
    pub fn inverse_transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation.inverse() * v
    }

    /// `self ∘ other`: `other` expressed in `self`'s frame, mapped to the parent frame.
    pub fn mul_pose(&self, other: &Pose) -> Pose {
        Pose {
            position: self.transform_point(other.position),
            rotation: (self.rotation * other.rotation).normalize(),
        }
    }
}

impl Default for Pose {
    fn default() -> Self {
        Pose::IDENTITY
    }
}

/// Collision and mass shape of a body, in the body's shape frame.
///
/// Round shapes (capsule, cylinder, cone) have their axis along the frame's local **Y**.
/// The shape frame's origin is the shape's geometric centre (for a cone: the centre of
/// its axis segment, base at `-half_height`, apex at `+half_height`), which is not the
/// centre of mass for a cone or a hull; see [`crate::scene::mass`].
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A box with the given half extents along local X, Y, Z.
    Box {
        /// Half extents (metres), all > 0.
        half_extents: Vec3,
    },
    /// A capsule: a segment of length `2·half_height` along local Y, swept by `radius`.
    Capsule {
        /// Half the length of the inner segment (metres), ≥ 0.
        half_height: f32,
        /// Radius (metres), > 0.
        radius: f32,
    },
    /// A cylinder along local Y. `sides` is the Doom 3 `numSides` (0 = round).
    Cylinder {
        /// Half height (metres), > 0.
        half_height: f32,
        /// Radius (metres), > 0.
        radius: f32,
        /// Polygon sides of the Doom 3 model (informational; 0 = smooth).
        sides: u32,
    },
    /// A cone along local Y: base at `-half_height`, apex at `+half_height`.
    Cone {
        /// Half height (metres), > 0.
        half_height: f32,
        /// Base radius (metres), > 0.
        radius: f32,
        /// Polygon sides of the Doom 3 model (informational; 0 = smooth).
        sides: u32,
    },
    /// The convex hull of a point cloud (Doom 3 octahedron, dodecahedron, bone, custom).
    ConvexHull {
        /// Hull points in the shape frame (shared, cheap to clone into snapshots).
        points: Arc<[Vec3]>,
    },
}

impl Shape {
    /// Half extents of the shape's local axis-aligned bounding box.
    pub fn local_half_extents(&self) -> Vec3 {
        match self {
            Shape::Box { half_extents } => *half_extents,
            Shape::Capsule {
                half_height,
                radius,
            } => Vec3::new(*radius, half_height + radius, *radius),
            Shape::Cylinder {
                half_height,
                radius,
                ..
            }
            | Shape::Cone {
                half_height,
                radius,
                ..
            } => Vec3::new(*radius, *half_height, *radius),
            Shape::ConvexHull { points } => {
                points.iter().fold(Vec3::ZERO, |acc, p| acc.max(p.abs()))
            }
        }
    }

    /// A short lowercase name for messages and summaries.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Capsule { .. } => "capsule",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Cone { .. } => "cone",
            Shape::ConvexHull { .. } => "convex hull",
        }
    }
}

/// How a body's mass is specified.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MassSpec {
    /// Mass = density · volume (kg/m³). Doom 3's `density`.
    Density(f32),
    /// A fixed total mass (kg); inertia follows from the shape at uniform density.
    Mass(f32),
}

/// Whether a body moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Motion {
    /// Integrated under gravity, contacts and joints.
    Dynamic,
    /// Never moves; infinite mass. Our extension (`fixed 1` in a body block).
    Fixed,
}

/// Doom 3 friction triple: air friction on translation and rotation, and contact friction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Friction {
    /// Translational air friction, a damping fraction per second in [0, 1].
    pub linear: f32,
    /// Rotational air friction, a damping fraction per second in [0, 1].
    pub angular: f32,
    /// Coulomb coefficient μ for contacts.
    pub contact: f32,
}

impl Default for Friction {
    fn default() -> Self {
        // Air friction off so closed-form tests hold; μ = 0.6 is a typical rubber-on-floor value.
        Friction {
            linear: 0.0,
            angular: 0.0,
            contact: 0.6,
        }
    }
}

/// One rigid body ("bone") of the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyDesc {
    /// Unique name (never `"world"`).
    pub name: String,
    /// Collision and mass shape.
    pub shape: Shape,
    /// World pose of the shape frame at rest.
    pub pose: Pose,
    /// Density or mass. After [`SceneDesc::resolve_masses`] (which the reader calls),
    /// always [`MassSpec::Mass`], with `totalMass` scaling applied.
    pub mass: MassSpec,
    /// Doom 3 `inertiaScale`: multiplies the body-space inertia tensor (row-major 3×3).
    pub inertia_scale: Option<[[f32; 3]; 3]>,
    /// Dynamic or fixed.
    pub motion: Motion,
    /// Air and contact friction.
    pub friction: Friction,
    /// Bounciness in [0, 1] for contacts involving this body (the larger of a pair is used).
    pub restitution: f32,
    /// Whether this body collides with other bodies of the same figure.
    pub self_collision: bool,
    /// Initial linear velocity (m/s).
    pub linear_velocity: Vec3,
    /// Initial angular velocity (rad/s, world space).
    pub angular_velocity: Vec3,
    /// Explicit particle positions in the shape frame for the particle method's `paper`
    /// mode (the paper places them by hand, test 2 variant 1 famously badly). `None`:
    /// the particle method places them itself.
    pub particles: Option<[Vec3; 4]>,
    /// Skeleton joint this body drives (Doom 3 `joint`), kept for reference.
    pub skeleton_joint: Option<String>,
    /// The skeleton joints whose parts of the visual mesh this body contains (Doom 3
    /// `containedJoints`), as sorted indices into the skeleton the figure was built on;
    /// a joint belongs to one body at most. A hit on the skinned mesh pushes the body
    /// containing the joint nearest to it. Empty for a figure without a skeleton.
    pub contained_joints: Vec<u32>,
}

impl BodyDesc {
    /// A dynamic body with defaults for everything but name, shape, pose and mass.
    pub fn new(name: impl Into<String>, shape: Shape, pose: Pose, mass: MassSpec) -> BodyDesc {
        BodyDesc {
            name: name.into(),
            shape,
            pose,
            mass,
            inertia_scale: None,
            motion: Motion::Dynamic,
            friction: Friction::default(),
            restitution: 0.0,
            self_collision: true,
            linear_velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
            particles: None,
            skeleton_joint: None,
            contained_joints: Vec::new(),
        }
    }

    /// True for fixed bodies.
    pub fn is_fixed(&self) -> bool {
        self.motion == Motion::Fixed
    }
}

/// The second body of a constraint: another body or the static world.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyRef {
    /// A body of the scene.
    Body(BodyId),
    /// The static world (Doom 3 `body2 "world"`).
    World,
}

impl BodyRef {
    /// The body, if this is not the world.
    pub fn body(self) -> Option<BodyId> {
        match self {
            BodyRef::Body(b) => Some(b),
            BodyRef::World => None,
        }
    }
}

/// A swing limit on a ball-and-socket or universal joint.
///
/// Doom 3 semantics: the `axis` is attached to body2 (or the world), the `shaft` to
/// body1; the shaft must stay inside the cone or pyramid around the axis. Both are unit
/// vectors given in world space at the rest pose (the shaft need not start on the axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SwingLimit {
    /// A circular cone of half-angle `half_angle` (radians, ≥ 0) around `axis`.
    Cone {
        /// Cone axis, attached to body2.
        axis: Vec3,
        /// Angle between the axis and the cone's surface (radians). Doom 3's
        /// `conelimit` gives the full apex angle; the reader halves it.
        half_angle: f32,
        /// Shaft, attached to body1.
        shaft: Vec3,
    },
    /// A pyramid: half-angles `half_angle1`, `half_angle2` (radians) in the two planes
    /// through `axis`, the pyramid rotated by `roll` about `axis`.
    Pyramid {
        /// Pyramid axis, attached to body2.
        axis: Vec3,
        /// Half-angle in the first plane.
        half_angle1: f32,
        /// Half-angle in the second plane.
        half_angle2: f32,
        /// Rotation of the pyramid about its axis (radians).
        roll: f32,
        /// Shaft, attached to body1.
        shaft: Vec3,
    },
}

/// A twist limit (our extension, and the PyODE tutorial's twist limit): the rotation of
/// body1 relative to body2 about `axis` (world space at rest, attached to body1), measured
/// from the rest pose, right-handed, must stay in `[min, max]` radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwistLimit {
    /// Twist axis at rest (unit, world space).
    pub axis: Vec3,
    /// Lower bound (radians, ≤ 0 for the rest pose to be legal).
    pub min: f32,
    /// Upper bound (radians).
    pub max: f32,
}

/// A range on a rotational degree of freedom, relative to the rest pose, in radians.
/// Angle convention: rotation of body1 relative to body2 about the joint axis,
/// right-handed, zero at the rest pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngleRange {
    /// Lower bound (radians).
    pub min: f32,
    /// Upper bound (radians).
    pub max: f32,
}

/// How a limit reacts when exceeded.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum LimitStyle {
    /// A hard stop (Doom 3, the paper).
    #[default]
    Hard,
    /// The PyODE tutorial's soft limit: a restoring torque of `torque · excess` (N·m/rad)
    /// once the limit is exceeded, like muscle tension; the joint may exceed it briefly.
    Soft {
        /// Restoring torque per radian of excess.
        torque: f32,
    },
}

/// The kind of a constraint and its type-specific data. Anchors and axes are world space
/// at the rest pose.
#[derive(Clone, Debug, PartialEq)]
pub enum JointKind {
    /// Ball-and-socket: the anchor point is shared, rotation is free up to the limits.
    BallAndSocket {
        /// Centre of the ball.
        anchor: Vec3,
        /// Optional swing limit (cone or pyramid).
        swing: Option<SwingLimit>,
        /// Optional twist limit.
        twist: Option<TwistLimit>,
        /// Hard or soft limits.
        limit_style: LimitStyle,
    },
    /// Universal: ball-and-socket that also keeps `shaft1` (body1) perpendicular to
    /// `shaft2` (body2), so no twist about either shaft.
    Universal {
        /// Joint anchor.
        anchor: Vec3,
        /// Rotation axis of the cross fixed in body1 (ODE's axis on body1). The `.af`
        /// reader derives it from Doom 3's `shafts` (which run along the bones) so that
        /// it is perpendicular to shaft 1 and to `shaft2`; see docs/af-format.md.
        shaft1: Vec3,
        /// Rotation axis of the cross fixed in body2, perpendicular to `shaft1` at rest.
        shaft2: Vec3,
        /// Optional swing limit on shaft1 (Doom 3 `conelimit` / `pyramidlimit`).
        swing: Option<SwingLimit>,
        /// Optional per-axis ranges (PyODE's lo/hi stops on axis 1 and axis 2).
        axis_ranges: Option<[AngleRange; 2]>,
    },
    /// Hinge: rotation about one axis only.
    Hinge {
        /// A point on the hinge axis.
        anchor: Vec3,
        /// Hinge axis (unit).
        axis: Vec3,
        /// Optional range relative to the rest pose.
        limit: Option<AngleRange>,
    },
    /// Slider (prismatic): translation along one axis only, no rotation.
    Slider {
        /// Slide axis (unit).
        axis: Vec3,
    },
    /// Fixed: no relative motion (PyODE's fixed joints in the spine).
    Fixed,
    /// Spring between an anchor on each body (Doom 3 `spring`).
    Spring {
        /// Anchor on body1.
        anchor1: Vec3,
        /// Anchor on body2 (or in the world).
        anchor2: Vec3,
        /// Spring constant when stretched (N/m).
        stretch: f32,
        /// Spring constant when compressed (N/m).
        compress: f32,
        /// Damping (N·s/m).
        damping: f32,
        /// Rest length (m).
        rest_length: f32,
        /// Minimum length (m), 0 for none.
        min_length: f32,
        /// Maximum length (m), 0 for none.
        max_length: f32,
    },
}

impl JointKind {
    /// Doom 3 keyword of this constraint type.
    pub fn keyword(&self) -> &'static str {
        match self {
            JointKind::BallAndSocket { .. } => "ballAndSocketJoint",
            JointKind::Universal { .. } => "universalJoint",
            JointKind::Hinge { .. } => "hinge",
            JointKind::Slider { .. } => "slider",
            JointKind::Fixed => "fixed",
            JointKind::Spring { .. } => "spring",
        }
    }

    /// The joint's anchor, where it has a single one.
    pub fn anchor(&self) -> Option<Vec3> {
        match self {
            JointKind::BallAndSocket { anchor, .. }
            | JointKind::Universal { anchor, .. }
            | JointKind::Hinge { anchor, .. } => Some(*anchor),
            _ => None,
        }
    }
}

/// A constraint between body1 and body2 (or the world).
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintDesc {
    /// Unique constraint name.
    pub name: String,
    /// First body.
    pub body1: BodyId,
    /// Second body or the world.
    pub body2: BodyRef,
    /// Type and type-specific data.
    pub kind: JointKind,
    /// Joint friction in [0, 1]: a capped motor holding relative rotation (Doom 3 `friction`).
    pub friction: f32,
}

/// The ground: an infinite horizontal plane `y = height` with its top at `height`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ground {
    /// Height of the ground's top surface (m).
    pub height: f32,
    /// Visual/collision thickness (m); the paper's test 4 variant 2 makes it 3× thicker.
    pub thickness: f32,
    /// Coulomb coefficient of the ground; a contact uses `sqrt(μ_body · μ_ground)`.
    pub friction: f32,
    /// Restitution of the ground.
    pub restitution: f32,
    /// Tilt of the ground plane about the world Z axis (radians), for slope tests.
    pub tilt: f32,
}

impl Default for Ground {
    fn default() -> Self {
        Ground {
            height: 0.0,
            thickness: 0.1,
            friction: 0.6,
            restitution: 0.0,
            tilt: 0.0,
        }
    }
}

impl Ground {
    /// Unit normal of the ground plane (Y tilted about Z by `tilt`).
    pub fn normal(&self) -> Vec3 {
        Vec3::new(-self.tilt.sin(), self.tilt.cos(), 0.0)
    }

    /// Signed height of a point above the plane, along its normal.
    pub fn height_of(&self, p: Vec3) -> f32 {
        self.normal().dot(p - Vec3::new(0.0, self.height, 0.0))
    }
}

/// Doom 3 `suspendSpeed` and the `noMove*` keys: when a figure may be put to sleep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SleepSettings {
    /// Max linear speed (m/s) at which a body may come to rest.
    pub linear_velocity: f32,
    /// Max angular speed (rad/s) at which a body may come to rest.
    pub angular_velocity: f32,
    /// Max linear acceleration (m/s²) at which a body may come to rest.
    pub linear_acceleration: f32,
    /// Max angular acceleration (rad/s²) at which a body may come to rest.
    pub angular_acceleration: f32,
    /// Seconds a figure must be below all thresholds before it sleeps (`noMoveTime`).
    pub time: f32,
    /// Max translation (m) over `time` to count as not moving (`noMoveTranslation`).
    pub translation: f32,
    /// Max rotation (rad) over `time` to count as not moving (`noMoveRotation`).
    pub rotation: f32,
    /// Never sleep before this many seconds (`minMoveTime`, 0 = none).
    pub min_move_time: f32,
    /// Force sleep after this many seconds (`maxMoveTime`, 0 = never).
    pub max_move_time: f32,
}

impl SleepSettings {
    /// Turns sleeping off: `noMoveTime` infinite, so no island is ever still for long
    /// enough, and no forced sleep (`maxMoveTime` 0). These two are all either method
    /// reads to put an island to sleep, so neither needs a check of its own. The speed
    /// thresholds stay, for what else reads them (the multibody's position pass holds
    /// bodies slower than them in place). The benchmarks' `--no-sleep`.
    pub fn disable(&mut self) {
        self.time = f32::INFINITY;
        self.max_move_time = 0.0;
    }

    /// Whether a body can ever fall asleep under these settings.
    pub fn enabled(&self) -> bool {
        self.time.is_finite() || self.max_move_time > 0.0
    }
}

impl Default for SleepSettings {
    fn default() -> Self {
        // Doom 3's defaults, converted to metres (suspendSpeed 20 30 40 60 in/s, deg/s...).
        SleepSettings {
            linear_velocity: 0.05,
            angular_velocity: 0.1,
            linear_acceleration: 1.0,
            angular_acceleration: 2.0,
            time: 0.5,
            translation: 0.01,
            rotation: 0.05,
            min_move_time: 0.0,
            max_move_time: 0.0,
        }
    }
}

/// An orbit camera's starting view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Eye position (m).
    pub eye: Vec3,
    /// Point looked at (m).
    pub target: Vec3,
}

impl Default for CameraDesc {
    fn default() -> Self {
        CameraDesc {
            eye: Vec3::new(0.0, 1.5, 5.0),
            target: Vec3::new(0.0, 0.7, 0.0),
        }
    }
}

/// Scene-wide settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Gravity (m/s²).
    pub gravity: Vec3,
    /// The ground plane, if any.
    pub ground: Option<Ground>,
    /// Simulated time per frame / per `T` key press (s). Default 1/60.
    pub timestep: f32,
    /// Constraint iterations: relaxation + projection rounds per step in the particle
    /// method's paper mode (the paper's N); the rigid-frames and XPBD solvers run
    /// substeps × iterations substeps. The multibody method's velocity iterations are
    /// [`Settings::multibody_iterations`].
    pub iterations: u32,
    /// Substeps per step for the improved particle solver and the multibody solver.
    pub substeps: u32,
    /// Substeps for the multibody solver alone, where a scene needs more of them than
    /// the particle method does (`None`: [`Settings::substeps`]). Stiffer soft
    /// constraints need more: the solver caps their frequency at a quarter of the
    /// substep rate.
    pub multibody_substeps: Option<u32>,
    /// Biased velocity iterations per substep for the multibody solver alone (`None`:
    /// [`Settings::iterations`]). Default 4: at 4 substeps the warm start carries most
    /// of the impulses from one substep to the next, and four iterations hold every
    /// closed form and robustness test and keep the pile of humans within 5.8 mm of
    /// penetration and 1.3° of limit excess, asleep as with five (1.4 s), for 7 % fewer
    /// instructions on the busy pile. At three a stack of ten boxes collapses (22 cm of
    /// penetration), a heavy box dropped on a light one sinks into it and hinge friction
    /// slips. A figure landing on one limb at 16 substeps and 240 Hz needs five
    /// ([`Settings::multibody_substeps`]): at three the paper's human falls asleep in 52
    /// of 72 nearby starts instead of 71.
    pub multibody_iterations: Option<u32>,
    /// Joint passes of the multibody solver's relax step per substep. The relax takes
    /// back the velocity the biased iterations added to push errors out; one
    /// Gauss–Seidel pass does not: a joint's angular rows (a limit, an alignment) act
    /// about the centre of mass, the point row then holds the anchor, and the two undo
    /// each other's work. A hinge door started 10° outside its range kept 2.6 % of the
    /// scene's energy scale as speed after one pass, 1.2 % after two, 0.6 % after three.
    pub relax_passes: u32,
    /// Substeps per step for the XPBD particle solver alone (`None`: substeps ×
    /// iterations, as the rigid-frames solver runs), each of
    /// [`Settings::xpbd_passes`] passes.
    pub xpbd_substeps: Option<u32>,
    /// Gauss–Seidel passes per substep of the XPBD particle solver over its contacts,
    /// joints and sticks. Default 8; `docs/benchmarks.md` weighs other schedules of
    /// substeps and passes against the gates.
    pub xpbd_passes: u32,
    /// Doom 3 `totalMass`: if > 0, every dynamic body's mass is scaled to make this total.
    pub total_mass: Option<f32>,
    /// When bodies may sleep.
    pub sleep: SleepSettings,
    /// Initial camera.
    pub camera: CameraDesc,
    /// Contact softness of the multibody solver: contact stiffness as a frequency (Hz),
    /// capped at a quarter of the substep rate. Default 60 Hz, the cap at the default
    /// 4 substeps of 1/60 s: a resting contact gives way by load / (m ω²), so at Box2D's
    /// 30 Hz a stack of ten boxes sags 2 cm; at 60 Hz each box stays within 1 cm.
    pub contact_hertz: f32,
    /// Joint stiffness of the multibody solver as a frequency (Hz).
    pub joint_hertz: f32,
    /// Damping ratio for contact and joint softness.
    pub damping_ratio: f32,
    /// Largest speed (m/s) at which contacts push apart bodies that overlap, such as
    /// bodies that start inside the ground or inside each other (Box2D's
    /// `contactPushMaxVelocity` / `maxContactPushSpeed`, 3 m/s there and by default
    /// here). The multibody solver clamps a soft contact's bias velocity to it, so a
    /// 25 cm overlap is removed in about 0.1 s instead of turning into a launch; the
    /// relax pass then takes the push velocity back, so the body does not fly on.
    /// Read from the `.af` `settings` key `maxPushOutSpeed` (file units per second).
    pub max_push_out_speed: f32,
    /// Relative normal speed (m/s) below which restitution is ignored.
    pub restitution_threshold: f32,
}

impl Settings {
    /// The multibody solver's substeps per step.
    pub fn multibody_substep_count(&self) -> u32 {
        self.multibody_substeps.unwrap_or(self.substeps)
    }

    /// The multibody solver's biased velocity iterations per substep.
    pub fn multibody_iteration_count(&self) -> u32 {
        self.multibody_iterations.unwrap_or(self.iterations)
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            gravity: Vec3::new(0.0, -9.81, 0.0),
            ground: Some(Ground::default()),
            timestep: 1.0 / 60.0,
            iterations: 5,
            substeps: 4,
            multibody_substeps: None,
            multibody_iterations: Some(4),
            relax_passes: 2,
            xpbd_substeps: None,
            xpbd_passes: crate::particle::XPBD_PASSES,
            total_mass: None,
            sleep: SleepSettings::default(),
            camera: CameraDesc::default(),
            contact_hertz: 60.0,
            joint_hertz: 60.0,
            damping_ratio: 10.0,
            max_push_out_speed: 3.0,
            restitution_threshold: 1.0,
        }
    }
}

/// A selectable variant of a scene (keys 1/2/3).
#[derive(Clone, Debug, PartialEq)]
pub struct VariantInfo {
    /// 1-based number, the key that selects it.
    pub number: u32,
    /// Short description ("the paper's aligned particles", "2 iterations", ...).
    pub name: String,
}

/// The whole scene: bodies, constraints and settings, with one variant applied.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SceneDesc {
    /// Scene name (file stem or the `name` extension key).
    pub name: String,
    /// Bodies, addressed by [`BodyId`].
    pub bodies: Vec<BodyDesc>,
    /// Constraints between them.
    pub constraints: Vec<ConstraintDesc>,
    /// Scene-wide settings (with the variant's overrides applied).
    pub settings: Settings,
    /// The variant this description was built for (1-based).
    pub variant: u32,
    /// All variants the scene offers; empty means only the default one.
    pub variants: Vec<VariantInfo>,
}

impl SceneDesc {
    /// Finds a body by name.
    pub fn body_id(&self, name: &str) -> Option<BodyId> {
        self.bodies
            .iter()
            .position(|b| b.name == name)
            .map(|i| BodyId(i as u32))
    }

    /// The body with this id.
    pub fn body(&self, id: BodyId) -> &BodyDesc {
        &self.bodies[id.index()]
    }

    /// Number of dynamic bodies.
    pub fn dynamic_body_count(&self) -> usize {
        self.bodies.iter().filter(|b| !b.is_fixed()).count()
    }
}
