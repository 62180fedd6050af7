// The skinned md5 mesh: each vertex is Σ biasₖ (Mₖ · (oₖ, 1)) over up to four weights,
// Mₖ the world matrix of weight k's joint (the joints the bodies drive), oₖ the weight's
// offset in that joint's frame, already in our units and axes. Joints are a uniform
// array (the device's limits offer no storage buffers on every adapter); weights are
// vertex attributes. Faces are lit flat with the normal from screen-space derivatives,
// turned toward the eye, so the file's winding does not matter.

struct Camera {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    light: vec4<f32>,
    ground: vec4<f32>,
};

@group(0) @binding(0) var<uniform> cam: Camera;

const MAX_JOINTS: u32 = 192u;

struct Skin {
    color: vec4<f32>,
    joints: array<mat4x4<f32>, 192>,
};

@group(1) @binding(0) var<uniform> skin: Skin;

struct SkinIn {
    // Offset (xyz) and bias (w) of weights 0..3; unused weights have bias 0.
    @location(0) w0: vec4<f32>,
    @location(1) w1: vec4<f32>,
    @location(2) w2: vec4<f32>,
    @location(3) w3: vec4<f32>,
    @location(4) joints: vec4<u32>,
};

struct SkinOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

fn weighted(w: vec4<f32>, j: u32) -> vec3<f32> {
    return w.w * (skin.joints[min(j, MAX_JOINTS - 1u)] * vec4<f32>(w.xyz, 1.0)).xyz;
}

@vertex
fn vs_skin(v: SkinIn) -> SkinOut {
    let p = weighted(v.w0, v.joints.x) + weighted(v.w1, v.joints.y)
        + weighted(v.w2, v.joints.z) + weighted(v.w3, v.joints.w);
    var out: SkinOut;
    out.clip = cam.view_proj * vec4<f32>(p, 1.0);
    out.world = p;
    return out;
}

@fragment
fn fs_skin(in: SkinOut) -> @location(0) vec4<f32> {
    let v = normalize(cam.eye.xyz - in.world);
    var n = normalize(cross(dpdx(in.world), dpdy(in.world)));
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    let l = -cam.light.xyz;
    let diffuse = max(dot(n, l), 0.0);
    let ambient = mix(0.22, 0.42, 0.5 + 0.5 * n.y);
    let rgb = skin.color.rgb * (ambient + 0.7 * diffuse);
    return vec4<f32>(rgb, 1.0);
}
