//! Joint limits: swing (Doom 3 cone and pyramid), twist, and angle ranges (hinge,
//! the PyODE universal joint's stops), hard or the PyODE tutorial's soft style.
//!
//! Every limit becomes one-dimensional angular rows ([`AxisRow`]) whose value `C` is
//! positive inside the limit; rows are recomputed from the current orientations each
//! substep. Doom 3 semantics: the swing *axis* (cone or pyramid) is attached to body2,
//! the *shaft* to body1.

use super::body::BodyStates;
use super::joint::{AlignPart, AxisRow, JointFrame, RowKind, RowState, unwrap_angle};
use super::joint_rows::AlignRows;
use super::soft::StepContext;
use crate::scene::{AngleRange, LimitStyle, SwingLimit, TwistLimit};
use glam::{Quat, Vec3};

/// Rows further than this from their bound (rad) are not solved.
pub(super) const MARGIN: f32 = 0.25;
/// Cone half-angles below this (rad) are solved as an exact alignment.
const TIGHT_CONE: f32 = 1e-3;

/// The row kind of a limit style.
pub fn row_kind(style: LimitStyle) -> RowKind {
    match style {
        LimitStyle::Hard => RowKind::Limit,
        LimitStyle::Soft { torque } => RowKind::SoftLimit { k: torque },
    }
}

/// The rows a swing limit sets at each substep ([`JointSolve::Rows`] of its joint): a
/// cone's one-dimensional row (the first of the four) or a pyramid's four, or a 0°
/// cone's two alignment rows. Each [`Swing::update`] makes the entry its own kind (an
/// entry of the step's row arrays may have held another joint's rows before), so the
/// swing itself holds no rows: what it keeps from step to step is its description and
/// its impulses.
///
/// [`JointSolve::Rows`]: super::joint::JointSolve::Rows
#[derive(Clone, Copy, Debug)]
pub(crate) enum SwingRows {
    /// A cone's row (the first) or a pyramid's four.
    Axis([AxisRow; 4]),
    /// A 0° cone's alignment rows.
    Align(AlignRows<f32>),
}

/// Inactive axis rows, never read before [`Swing::update`].
impl Default for SwingRows {
    fn default() -> SwingRows {
        SwingRows::Axis([AxisRow::default(); 4])
    }
}

impl SwingRows {
    /// The axis rows, made the entry's kind.
    pub(crate) fn axis_mut(&mut self) -> &mut [AxisRow; 4] {
        if !matches!(self, SwingRows::Axis(_)) {
            *self = SwingRows::default();
        }
        match self {
            SwingRows::Axis(rows) => rows,
            SwingRows::Align(_) => unreachable!("made axis rows above"),
        }
    }

    /// The alignment rows, made the entry's kind.
    fn align_mut(&mut self) -> &mut AlignRows<f32> {
        if !matches!(self, SwingRows::Align(_)) {
            *self = SwingRows::Align(AlignRows::default());
        }
        match self {
            SwingRows::Align(rows) => rows,
            SwingRows::Axis(_) => unreachable!("made alignment rows above"),
        }
    }

    /// A cone's row: the first axis row (an inactive row for alignment rows).
    pub(crate) fn first(&self) -> AxisRow {
        match self {
            SwingRows::Axis(rows) => rows[0],
            SwingRows::Align(_) => AxisRow::default(),
        }
    }
}

/// A swing limit in body space: its description and the accumulated impulses of its
/// rows (the rows themselves are the step's, [`SwingRows`]).
#[derive(Clone, Copy, Debug)]
pub enum Swing {
    /// Shaft within `half_angle` of the axis; `C = half_angle − ∠(axis, shaft)`.
    Cone {
        /// Axis in b.
        axis_b: Vec3,
        /// Shaft in a.
        shaft_a: Vec3,
        /// Half-angle (rad).
        half_angle: f32,
        /// Its cosine: a shaft whose cosine with the axis is at least this is inside.
        cos_half: f32,
        /// The row's state (its row is the first of [`SwingRows`]).
        row: RowState,
    },
    /// A 0° cone: shaft and axis locked together (two bilateral rows); the part's
    /// directions are the shaft in a and the axis in b.
    Tight(AlignPart),
    /// Shaft inside four planes through the axis, tilted by ±half_angle1 towards `side1`
    /// and ±half_angle2 towards `side2`: `C_k = −shaft · n_k`.
    Pyramid {
        /// Axis in b.
        axis_b: Vec3,
        /// First side direction in b (perpendicular to the axis, roll applied).
        side1_b: Vec3,
        /// Second side direction in b.
        side2_b: Vec3,
        /// Shaft in a.
        shaft_a: Vec3,
        /// Half-angles.
        half: [f32; 2],
        /// How the four side rows react (one kind for all four).
        kind: RowKind,
        /// The accumulated impulses of the side rows, one per plane.
        impulse: [f32; 4],
    },
}

impl Swing {
    /// Body-space limit from the scene's world-space description at rest.
    pub fn new(f: &JointFrame, s: &BodyStates, limit: &SwingLimit, style: LimitStyle) -> Swing {
        let kind = row_kind(style);
        match *limit {
            SwingLimit::Cone {
                axis,
                half_angle,
                shaft,
            } => {
                if half_angle < TIGHT_CONE && kind == RowKind::Limit {
                    // Align the shaft (in a) with the axis (in b). At rest they may differ;
                    // the tight cone then holds the shaft on the axis from the first step.
                    let mut part = AlignPart::new(f, s, axis);
                    part.local_a = f.dir_in_a(s, shaft);
                    Swing::Tight(part)
                } else {
                    Swing::Cone {
                        axis_b: f.dir_in_b(s, axis),
                        shaft_a: f.dir_in_a(s, shaft),
                        half_angle,
                        cos_half: half_angle.cos(),
                        row: RowState::new(kind),
                    }
                }
            }
            SwingLimit::Pyramid {
                axis,
                half_angle1,
                half_angle2,
                roll,
                shaft,
            } => {
                let (u, v) = crate::scene::pyramid_sides(axis, roll);
                Swing::Pyramid {
                    axis_b: f.dir_in_b(s, axis),
                    side1_b: f.dir_in_b(s, u),
                    side2_b: f.dir_in_b(s, v),
                    shaft_a: f.dir_in_a(s, shaft),
                    half: [half_angle1, half_angle2],
                    kind,
                    impulse: [0.0; 4],
                }
            }
        }
    }

    /// Plane normals of the pyramid, world: the plane through the axis tilted by `h`
    /// towards `side` has normal `cos h · side − sin h · axis` (outward).
    fn pyramid_normals(axis: Vec3, s1: Vec3, s2: Vec3, half: [f32; 2]) -> [Vec3; 4] {
        let (c1, n1) = (half[0].cos(), half[0].sin());
        let (c2, n2) = (half[1].cos(), half[1].sin());
        [
            c1 * s1 - n1 * axis,
            -c1 * s1 - n1 * axis,
            c2 * s2 - n2 * axis,
            -c2 * s2 - n2 * axis,
        ]
    }

    /// Recomputes the rows from the current pose.
    pub(crate) fn update(&mut self, set: &mut SwingRows, f: &JointFrame, s: &BodyStates) {
        match self {
            Swing::Cone {
                axis_b,
                shaft_a,
                half_angle,
                row,
                ..
            } => {
                let a = s.rot[f.b] * *axis_b;
                let sh = s.rot[f.a] * *shaft_a;
                let phi = a.dot(sh).clamp(-1.0, 1.0).acos();
                // φ̇ = n · (ω_a − ω_b) with n the unit rotation axis from `a` to the shaft.
                let n = a.cross(sh);
                let n = if n.length_squared() > 1e-12 {
                    n.normalize()
                } else {
                    a.any_orthonormal_vector()
                };
                let value = (-n, *half_angle - phi);
                set.axis_mut()[0].set((row.kind, &mut row.impulse), f, s, value, MARGIN);
            }
            Swing::Tight(part) => part.prepare(set.align_mut(), f, s),
            Swing::Pyramid {
                axis_b,
                side1_b,
                side2_b,
                shaft_a,
                half,
                kind,
                impulse,
            } => {
                let rb = s.rot[f.b];
                let normals =
                    Self::pyramid_normals(rb * *axis_b, rb * *side1_b, rb * *side2_b, *half);
                let sh = s.rot[f.a] * *shaft_a;
                let rows = set.axis_mut().iter_mut().zip(impulse);
                for ((row, impulse), n) in rows.zip(normals) {
                    // d(shaft·n)/dt = (ω_a − ω_b)·(shaft × n).
                    let c = -sh.dot(n);
                    row.set((*kind, impulse), f, s, (-sh.cross(n), c), MARGIN);
                }
            }
        }
    }

    /// Whether this is a hard limit (the PyODE tutorial's soft limits are springs).
    pub fn is_hard(&self) -> bool {
        match self {
            Swing::Cone { row, .. } => row.kind == RowKind::Limit,
            Swing::Tight(_) => true,
            Swing::Pyramid { kind, .. } => *kind == RowKind::Limit,
        }
    }

    /// How far outside the limit the shaft is now (rad, 0 inside).
    pub fn violation(&self, f: &JointFrame, s: &BodyStates) -> f32 {
        match self {
            Swing::Cone {
                axis_b,
                shaft_a,
                half_angle,
                ..
            } => {
                let a = s.rot[f.b] * *axis_b;
                let sh = s.rot[f.a] * *shaft_a;
                (a.dot(sh).clamp(-1.0, 1.0).acos() - half_angle).max(0.0)
            }
            Swing::Tight(p) => {
                let a = s.rot[f.b] * p.local_b;
                let sh = s.rot[f.a] * p.local_a;
                a.dot(sh).clamp(-1.0, 1.0).acos()
            }
            Swing::Pyramid {
                axis_b,
                side1_b,
                side2_b,
                shaft_a,
                half,
                ..
            } => {
                let rb = s.rot[f.b];
                let sh = s.rot[f.a] * *shaft_a;
                Self::pyramid_normals(rb * *axis_b, rb * *side1_b, rb * *side2_b, *half)
                    .iter()
                    .map(|n| sh.dot(*n).clamp(-1.0, 1.0).asin().max(0.0))
                    .fold(0.0, f32::max)
            }
        }
    }

    /// Re-applies accumulated impulses along the rows `set` (set by this swing's
    /// [`Swing::update`]).
    pub(crate) fn warm_start(&self, set: &SwingRows, f: &JointFrame, s: &mut BodyStates) {
        match (self, set) {
            (Swing::Cone { row, .. }, SwingRows::Axis(set)) => set[0].warm_start(row.impulse, f, s),
            (Swing::Tight(part), SwingRows::Align(rows)) => part.warm_start(rows, f, s),
            (Swing::Pyramid { impulse, .. }, SwingRows::Axis(set)) => {
                (set.iter().zip(impulse)).for_each(|(r, &i)| r.warm_start(i, f, s))
            }
            _ => unreachable!("the swing's update set its kind of rows"),
        }
    }

    /// The 0° cone's alignment rows prepared on the moved pose, for the relax pass
    /// (see [`super::joint::JointSolve::prepare_moved`]); the other rows keep theirs.
    pub(crate) fn prepare_moved(&self, set: &mut SwingRows, f: &JointFrame, s: &BodyStates) {
        if let Swing::Tight(part) = self {
            part.prepare(set.align_mut(), f, s);
        }
    }

    /// One update of every row of `set`.
    pub(crate) fn solve(
        &mut self,
        set: &SwingRows,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        match (self, set) {
            (Swing::Cone { row, .. }, SwingRows::Axis(set)) => {
                set[0].solve(&mut row.impulse, f, s, ctx, use_bias)
            }
            (Swing::Tight(part), SwingRows::Align(rows)) => part.solve(rows, f, s, ctx, use_bias),
            (Swing::Pyramid { impulse, .. }, SwingRows::Axis(set)) => {
                (set.iter().zip(impulse)).for_each(|(r, i)| r.solve(i, f, s, ctx, use_bias))
            }
            _ => unreachable!("the swing's update set its kind of rows"),
        }
    }

    /// Position projection of the hard rows, measured on the current pose (the rows of
    /// the velocity solve are left as they are, for the warm start).
    pub fn project(&self, f: &JointFrame, s: &mut BodyStates) {
        // Soft limits are springs: the projection leaves them alone (`AxisRow::project`).
        if !self.is_hard() {
            return;
        }
        if let Swing::Cone {
            axis_b,
            shaft_a,
            cos_half,
            ..
        } = self
        {
            // A shaft inside the cone has `C ≥ 0` (to rounding, far within the slop) and
            // nothing to project: a dot product tells, where measuring the row takes an
            // arccosine and a normalisation.
            if (s.rot[f.b] * *axis_b).dot(s.rot[f.a] * *shaft_a) >= *cos_half {
                return;
            }
        }
        let mut now = *self;
        let mut set = SwingRows::default();
        now.update(&mut set, f, s);
        match (&now, &set) {
            (Swing::Cone { .. }, SwingRows::Axis(set)) => set[0].project(f, s),
            (Swing::Tight(part), _) => part.project(f, s),
            (Swing::Pyramid { .. }, SwingRows::Axis(set)) => {
                set.iter().for_each(|r| r.project(f, s))
            }
            _ => unreachable!("the swing's update set its kind of rows"),
        }
    }

    /// World axis and half-angle for drawing (the pyramid drawn as its wider cone).
    pub fn draw_cone(&self, f: &JointFrame, s: &BodyStates) -> (Vec3, f32) {
        match self {
            Swing::Cone {
                axis_b, half_angle, ..
            } => (s.rot[f.b] * *axis_b, *half_angle),
            Swing::Tight(part) => (s.rot[f.b] * part.local_b, 0.0),
            Swing::Pyramid { axis_b, half, .. } => (s.rot[f.b] * *axis_b, half[0].max(half[1])),
        }
    }
}

/// The rotation of body1 relative to body2 about an axis, measured from the rest pose,
/// right-handed, followed continuously past ±π. Reference directions perpendicular to
/// the axis are fixed in each body; body2's is first swung onto the plane perpendicular
/// to body1's axis by the shortest arc, so swing does not read as twist.
///
/// That angle is the twist of the swing–twist split of body1's rotation from rest seen
/// in body2's frame, `d = q_b⁻¹ q_a q₀⁻¹ = S T` (`q₀` the rest value of `q_b⁻¹ q_a`,
/// `T` a turn by θ about the axis, `S` the shortest arc taking the axis where `d` takes
/// it): `S` carries body2's reference onto the plane across body1's axis and body1's
/// reference is `S T` of it, so the angle between the two is θ. With `T` the twist part
/// of `d`, `θ = 2 atan2(d_xyz · axis, d_w)` (`d_w ≥ 0`): two quaternion products and an
/// arctangent, rather than rotating four directions and forming the arc: a limit is
/// measured at every substep, so this reading is on the solver's hot path.
///
/// The axis is body1's unless [`AngleGauge::on_body2`] is set: a universal joint's
/// second shaft is fixed in body2, and once body1 has turned about the first shaft its
/// copy of the second points elsewhere (90° of hip flexion turns it onto the first
/// shaft's old neighbour), so pushing about body1's copy mixes the two angles and the
/// stop pushes about the wrong axis. (The angle is the same about either copy: swinging
/// body1's reference onto body2's plane instead gives `S⁻¹ d = T` of it.)
#[derive(Clone, Copy, Debug)]
pub struct AngleGauge {
    /// Axis in a.
    pub axis_a: Vec3,
    /// Axis in b.
    pub axis_b: Vec3,
    /// Reference direction in b (where the angle reads 0, for drawing).
    pub ref_b: Vec3,
    /// `q₀⁻¹`: the inverse of body1's rest orientation seen from body2, as the
    /// quaternion's `[x, y, z, w]`: a `Quat`'s 16-byte alignment would pad every limit,
    /// and with it every joint holding one, to a multiple of 16 bytes.
    rest_inv: [f32; 4],
    /// Last unwrapped angle (rad).
    pub angle: f32,
    /// Measure about body2's copy of the axis, swinging body1's reference onto it.
    pub on_body2: bool,
}

impl AngleGauge {
    /// A gauge about the world `axis` at rest, reading 0 now.
    pub fn new(f: &JointFrame, s: &BodyStates, axis: Vec3) -> AngleGauge {
        AngleGauge {
            axis_a: f.dir_in_a(s, axis),
            axis_b: f.dir_in_b(s, axis),
            ref_b: f.dir_in_b(s, axis.any_orthonormal_vector()),
            rest_inv: (s.rot[f.b].inverse() * s.rot[f.a]).inverse().to_array(),
            angle: 0.0,
            on_body2: false,
        }
    }

    /// Current world axis (body1's, or body2's with [`AngleGauge::on_body2`]) and
    /// unwrapped angle, without updating the memory.
    pub fn measure(&self, f: &JointFrame, s: &BodyStates) -> (Vec3, f32) {
        let d = s.rot[f.b].inverse() * s.rot[f.a] * Quat::from_array(self.rest_inv);
        // `d` and `−d` are the same rotation; with `d_w ≥ 0` the angle is in [−π, π].
        let (sin, cos) = (d.xyz().dot(self.axis_b), d.w);
        let raw = 2.0
            * if cos < 0.0 {
                (-sin).atan2(-cos)
            } else {
                sin.atan2(cos)
            };
        let axis = if self.on_body2 {
            s.rot[f.b] * self.axis_b
        } else {
            s.rot[f.a] * self.axis_a
        };
        (axis, unwrap_angle(self.angle, raw))
    }
}

/// A `[min, max]` range on an [`AngleGauge`]: a hinge limit, a twist limit, one axis
/// of a universal joint.
#[derive(Clone, Copy, Debug)]
pub struct AngleLimit {
    /// The angle measured.
    pub gauge: AngleGauge,
    /// Bounds (rad).
    pub range: AngleRange,
    /// How both rows react.
    pub kind: RowKind,
    /// The accumulated impulses of the lower and upper rows (the rows are
    /// [`RangeRows`]).
    pub impulse: [f32; 2],
}

/// The lower and upper rows an [`AngleLimit`] sets at each substep.
pub(crate) type RangeRows = [AxisRow; 2];

impl AngleLimit {
    /// A limit about the world `axis` at rest.
    pub fn new(
        f: &JointFrame,
        s: &BodyStates,
        axis: Vec3,
        range: AngleRange,
        style: LimitStyle,
    ) -> AngleLimit {
        let kind = row_kind(style);
        AngleLimit {
            gauge: AngleGauge::new(f, s, axis),
            range,
            kind,
            impulse: [0.0; 2],
        }
    }

    /// The same limit measured about body2's copy of the axis (see
    /// [`AngleGauge::on_body2`]).
    pub fn about_body2(mut self) -> AngleLimit {
        self.gauge.on_body2 = true;
        self
    }

    /// From a twist limit.
    pub fn twist(f: &JointFrame, s: &BodyStates, t: &TwistLimit, style: LimitStyle) -> AngleLimit {
        AngleLimit::new(
            f,
            s,
            t.axis,
            AngleRange {
                min: t.min,
                max: t.max,
            },
            style,
        )
    }

    /// Measures the angle (remembering it for unwrapping) and sets the rows.
    pub(crate) fn update(&mut self, set: &mut RangeRows, f: &JointFrame, s: &BodyStates) {
        let (axis, angle) = self.gauge.measure(f, s);
        self.gauge.angle = angle;
        let [lower, upper] = &mut self.impulse;
        let kind = self.kind;
        set[0].set((kind, lower), f, s, (axis, angle - self.range.min), MARGIN);
        set[1].set((kind, upper), f, s, (-axis, self.range.max - angle), MARGIN);
    }

    /// Whether this is a hard limit (the PyODE tutorial's soft limits are springs).
    pub fn is_hard(&self) -> bool {
        self.kind == RowKind::Limit
    }

    /// Excess beyond the range now (rad).
    pub fn violation(&self, f: &JointFrame, s: &BodyStates) -> f32 {
        let (_, a) = self.gauge.measure(f, s);
        (self.range.min - a).max(a - self.range.max).max(0.0)
    }

    /// Re-applies accumulated impulses along the rows `set`.
    pub(crate) fn warm_start(&self, set: &RangeRows, f: &JointFrame, s: &mut BodyStates) {
        (set.iter().zip(&self.impulse)).for_each(|(r, &i)| r.warm_start(i, f, s));
    }

    /// Position projection of the range, measured on the current pose without touching
    /// the solver's rows or the unwrapping memory.
    pub fn project(&self, f: &JointFrame, s: &mut BodyStates) {
        // Soft limits are springs: the projection leaves them alone (`AxisRow::project`).
        if !self.is_hard() {
            return;
        }
        let mut now = *self;
        let mut set = RangeRows::default();
        now.update(&mut set, f, s);
        set.iter().for_each(|r| r.project(f, s));
    }

    /// One update of both rows of `set`.
    pub(crate) fn solve(
        &mut self,
        set: &RangeRows,
        f: &JointFrame,
        s: &mut BodyStates,
        ctx: &StepContext,
        use_bias: bool,
    ) {
        (set.iter().zip(&mut self.impulse)).for_each(|(r, i)| r.solve(i, f, s, ctx, use_bias));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::EulerRot;

    /// Body1 turned by θ about the hinge axis and then swung, the pair turned as a
    /// whole: the gauge reads θ about either body's copy of the axis, whatever the swing,
    /// and gives that copy as the axis.
    #[test]
    fn the_gauge_reads_the_twist_and_not_the_swing() {
        let rest_a = Quat::from_euler(EulerRot::XYZ, 0.3, -1.1, 0.7);
        let rest_b = Quat::from_euler(EulerRot::XYZ, -0.4, 0.2, 2.0);
        let axis = Vec3::new(0.3, 0.9, -0.2).normalize();
        let (side1, side2) = axis.any_orthonormal_pair();
        let mut s = BodyStates::with_capacity(2);
        s.push(Vec3::ZERO, rest_a, Vec3::ZERO, Vec3::ZERO);
        s.push(Vec3::X, rest_b, Vec3::ZERO, Vec3::ZERO);
        let f = JointFrame::new(&s, 0, 1, Vec3::new(0.5, 0.0, 0.0));
        let mut gauge = AngleGauge::new(&f, &s, axis);
        let whole = Quat::from_euler(EulerRot::ZYX, 0.5, -0.9, 1.7);
        let swings = [
            Quat::IDENTITY,
            Quat::from_axis_angle(side1, 0.8),
            Quat::from_axis_angle((side1 - 2.0 * side2).normalize(), -1.3),
        ];
        for theta in [-3.1, -1.2, -0.01, 0.0, 0.4, 2.5, 3.1] {
            for swing in swings {
                s.rot[1] = whole * rest_b;
                s.rot[0] = whole * swing * Quat::from_axis_angle(axis, theta) * rest_a;
                for on_body2 in [false, true] {
                    gauge.on_body2 = on_body2;
                    let (copy, angle) = gauge.measure(&f, &s);
                    let expected = if on_body2 {
                        whole * axis
                    } else {
                        whole * swing * axis
                    };
                    assert!((angle - theta).abs() < 1e-4, "θ {theta}: read {angle}");
                    assert!(copy.distance(expected) < 1e-5, "axis {copy} not {expected}");
                }
            }
        }
    }
}
