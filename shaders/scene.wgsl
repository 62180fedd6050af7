// Lit instanced shapes, their planar shadows, the ground grid and debug lines.
//
// One camera uniform per viewport. The ground is the plane dot(n, p) = d (n = ground.xyz,
// d = ground.w); shadows are the shapes squashed onto that plane along the light direction
// (Blinn's planar projection), drawn once per pixel thanks to the stencil buffer.

struct Camera {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    // Direction the light travels (unit), w unused.
    light: vec4<f32>,
    // Ground plane (normal, offset).
    ground: vec4<f32>,
};

@group(0) @binding(0) var<uniform> cam: Camera;

struct MeshIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) cap: f32,
};

struct InstanceIn {
    @location(3) m0: vec4<f32>,
    @location(4) m1: vec4<f32>,
    @location(5) m2: vec4<f32>,
    @location(6) m3: vec4<f32>,
    // Scale of the unit mesh (xyz) and the capsule half-height (w).
    @location(7) params: vec4<f32>,
    @location(8) color: vec4<f32>,
};

struct MeshOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
};

fn world_of(v: MeshIn, i: InstanceIn) -> vec3<f32> {
    let model = mat4x4<f32>(i.m0, i.m1, i.m2, i.m3);
    let local = v.position * i.params.xyz + vec3<f32>(0.0, v.cap * i.params.w, 0.0);
    return (model * vec4<f32>(local, 1.0)).xyz;
}

@vertex
fn vs_mesh(v: MeshIn, i: InstanceIn) -> MeshOut {
    let model = mat4x4<f32>(i.m0, i.m1, i.m2, i.m3);
    let world = world_of(v, i);
    // Axis-aligned scaling: the normal transforms by the inverse scale.
    let n_local = normalize(v.normal / i.params.xyz);
    var out: MeshOut;
    out.clip = cam.view_proj * vec4<f32>(world, 1.0);
    out.world = world;
    out.normal = (model * vec4<f32>(n_local, 0.0)).xyz;
    out.color = i.color;
    return out;
}

@fragment
fn fs_mesh(in: MeshOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let l = -cam.light.xyz;
    let v = normalize(cam.eye.xyz - in.world);
    let h = normalize(l + v);
    let diffuse = max(dot(n, l), 0.0);
    // Sky/ground hemisphere ambient keeps the unlit sides readable.
    let ambient = mix(0.22, 0.42, 0.5 + 0.5 * n.y);
    let spec = pow(max(dot(n, h), 0.0), 48.0) * 0.25;
    let rgb = in.color.rgb * (ambient + 0.7 * diffuse) + vec3<f32>(spec);
    return vec4<f32>(rgb, in.color.a);
}

struct ShadowOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) alpha: f32,
};

@vertex
fn vs_shadow(v: MeshIn, i: InstanceIn) -> ShadowOut {
    let p = world_of(v, i);
    let n = cam.ground.xyz;
    let l = cam.light.xyz;
    let above = dot(n, p) - cam.ground.w;
    // Slide p along the light onto the plane, lifted 2 mm against z-fighting.
    let q = p - l * (above / dot(n, l)) + n * 0.002;
    var out: ShadowOut;
    out.clip = cam.view_proj * vec4<f32>(q, 1.0);
    // Fade shadows of bodies high above the ground; none for parts below it.
    out.alpha = select(0.45 * clamp(1.0 - above / 6.0, 0.0, 1.0), 0.0, above < -0.01);
    return out;
}

@fragment
fn fs_shadow(in: ShadowOut) -> @location(0) vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.0, in.alpha);
}

struct GroundOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_ground(@location(0) position: vec3<f32>) -> GroundOut {
    var out: GroundOut;
    out.clip = cam.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    return out;
}

fn grid_line(coord: vec2<f32>, spacing: f32) -> f32 {
    let c = coord / spacing;
    let w = fwidth(c);
    let g = abs(fract(c - 0.5) - 0.5) / max(w, vec2<f32>(1e-4));
    return 1.0 - min(min(g.x, g.y), 1.0);
}

@fragment
fn fs_ground(in: GroundOut) -> @location(0) vec4<f32> {
    // Grid in the plane's own coordinates: x along the tilted slope, z across.
    let n = cam.ground.xyz;
    let tangent = normalize(vec3<f32>(n.y, -n.x, 0.0));
    let coord = vec2<f32>(dot(in.world, tangent), in.world.z);
    let minor = grid_line(coord, 0.5);
    let major = grid_line(coord, 2.5);
    let dist = length(in.world - cam.eye.xyz);
    let fade = clamp(1.0 - dist / 40.0, 0.0, 1.0);
    let base = vec3<f32>(0.50, 0.50, 0.48);
    let lit = base * (0.55 + 0.45 * max(dot(n, -cam.light.xyz), 0.0));
    let rgb = mix(lit, lit * 0.55, max(minor * 0.5, major) * fade);
    return vec4<f32>(rgb, 1.0);
}

struct LineOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_line(@location(0) position: vec3<f32>, @location(1) color: vec4<f32>) -> LineOut {
    var out: LineOut;
    out.clip = cam.view_proj * vec4<f32>(position, 1.0);
    out.color = color;
    return out;
}

@fragment
fn fs_line(in: LineOut) -> @location(0) vec4<f32> {
    return in.color;
}
