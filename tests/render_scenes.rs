//! Every built-in scene captured offscreen through the CLI (`ragdoll-lab capture`), on the
//! software adapter in CI, with assertions on the pixels. One binary, one capture run per
//! scene (frames 0 and 120 from a single `--every 120` run) to keep llvmpipe time small.

use ragdoll_lab::capture::half_aspect;
use ragdoll_lab::cli::SceneArgs;
use ragdoll_lab::picking;
use ragdoll_lab::render::camera::OrbitCamera;
use ragdoll_lab::render::{Viewport, split};
use ragdoll_lab::scenes;
use ragdoll_sim::snapshot::RenderSnapshot;
use std::path::{Path, PathBuf};
use std::process::Command;

const W: u32 = 640;
const H: u32 = 360;

/// Bands the text overlays use (labels at the top, the clock at the bottom, in a
/// 360 px view with 8 px text): pixel tests ignore them.
const TOP_BAND: u32 = 40;
const BOTTOM_BAND: u32 = 30;

/// "Blue" / "red": that channel beats both others by more than 40 of 255. The sky, the
/// grey ground with its grid, shadows, white sticks and the labels' grey boxes differ
/// by less than 20 between channels; the palette's blues and reds, lit or in shade, by
/// more than 60.
const MARGIN: i32 = 40;

struct Png {
    width: u32,
    rgba: Vec<u8>,
}

impl Png {
    fn read(path: &Path) -> Png {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
        ));
        let mut reader = decoder.read_info().unwrap();
        let mut rgba = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut rgba).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgba);
        assert_eq!((info.width, info.height), (W, H));
        Png {
            width: info.width,
            rgba,
        }
    }

    fn px(&self, x: u32, y: u32) -> [i32; 3] {
        let i = ((y * self.width + x) * 4) as usize;
        [0, 1, 2].map(|c| self.rgba[i + c] as i32)
    }
}

fn blue(p: [i32; 3]) -> bool {
    p[2] - p[0].max(p[1]) > MARGIN
}

fn red(p: [i32; 3]) -> bool {
    p[0] - p[1].max(p[2]) > MARGIN
}

/// (blue, red) pixel counts in columns `x0..x1`, outside the text bands.
fn count(img: &Png, x0: u32, x1: u32) -> (usize, usize) {
    let (mut b, mut r) = (0, 0);
    for y in TOP_BAND..H - BOTTOM_BAND {
        for x in x0..x1 {
            let p = img.px(x, y);
            b += blue(p) as usize;
            r += red(p) as usize;
        }
    }
    (b, r)
}

fn capture(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ragdoll-lab"))
        .arg("capture")
        .args(args)
        .output()
        .expect("run ragdoll-lab")
}

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn every_scene_is_blue_left_red_right_with_bodies_in_place_and_moving() {
    let size = format!("{W}x{H}");
    let mut report = Vec::new();
    for scene in scenes::builtin_scenes() {
        let number = scene.number.to_string();
        let dir = out_dir(&format!("scene-{number}"));
        let out = capture(&[
            "--scene",
            &number,
            "--frames",
            "120",
            "--every",
            "120",
            "--size",
            &size,
            "--out-dir",
            dir.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "scene {}: {}",
            scene.name,
            String::from_utf8_lossy(&out.stderr)
        );
        let first = Png::read(&dir.join("frame_00000.png"));
        let last = Png::read(&dir.join("frame_00120.png"));

        // Colours per half. The particle side also shows red internal particles (the
        // paper's colouring) over its bodies: a few dozen pixels against thousands.
        let half = W / 2;
        let (lb, lr) = count(&first, 0, half);
        let (rb, rr) = count(&first, half, W);
        report.push(format!(
            "{}: left {lb} blue {lr} red, right {rb} blue {rr} red",
            scene.name
        ));
        // A visible body covers at least ~150 px² of a 320×290 half here (the smallest,
        // the limit scenes' boxes, ~15×10 px each).
        assert!(lb > 150, "{}: left half has {lb} blue pixels", scene.name);
        assert!(rr > 150, "{}: right half has {rr} red pixels", scene.name);
        assert!(
            lr * 4 < lb,
            "{}: left half {lb} blue vs {lr} red",
            scene.name
        );
        assert!(
            rb * 20 < rr,
            "{}: right half {rr} red vs {rb} blue",
            scene.name
        );

        // Bodies where the scene puts them: each body's rest position, projected with the
        // scene's camera into each half, has a body-coloured pixel within 4 px. Centres
        // behind another body still land on that body's colour; centres under the text
        // bands or outside the view are skipped. At least 3 in 4 must match (a particle
        // or stick drawn over a centre can hide it).
        let loaded = scenes::load(&SceneArgs {
            scene: Some(number.clone()),
            ..Default::default()
        })
        .unwrap();
        // The camera capture uses: the scene's, pulled back where the bodies at rest do
        // not fit clear of the labels.
        let rest = RenderSnapshot::from_scene_rest(&loaded.desc);
        let camera = picking::scene_camera(
            OrbitCamera::from_desc(&loaded.desc.settings.camera),
            &[rest.clone(), rest],
            half_aspect(W, H, false),
        );
        let halves = split(Viewport {
            x: 0.0,
            y: 0.0,
            width: W as f32,
            height: H as f32,
        });
        for (vp, is_side) in [(halves[0], blue as fn([i32; 3]) -> bool), (halves[1], red)] {
            let (mut seen, mut found) = (0, 0);
            for body in &loaded.desc.bodies {
                let Some(p) = vp.project(&camera, body.pose.position) else {
                    continue;
                };
                let (x, y) = (p.x.round() as i64, p.y.round() as i64);
                if x < vp.x as i64 + 4
                    || x >= (vp.x + vp.width) as i64 - 4
                    || y < TOP_BAND as i64 + 4
                    || y >= (H - BOTTOM_BAND) as i64 - 4
                {
                    continue;
                }
                seen += 1;
                let hit = (-4..=4).any(|dy| {
                    (-4..=4).any(|dx| is_side(first.px((x + dx) as u32, (y + dy) as u32)))
                });
                found += hit as usize;
            }
            assert!(seen > 0, "{}: no body in view", scene.name);
            assert!(
                found * 4 >= seen * 3,
                "{}: {found} of {seen} bodies where the scene puts them",
                scene.name
            );
        }

        // Every scene has dynamic bodies that fall or swing in the first two seconds:
        // frame 120 differs from frame 0 in more than 0.5 % of the pixels outside the
        // text bands (by more than 30 of 255 in some channel).
        assert!(loaded.desc.dynamic_body_count() > 0);
        let mut changed = 0;
        for y in TOP_BAND..H - BOTTOM_BAND {
            for x in 0..W {
                let (a, b) = (first.px(x, y), last.px(x, y));
                changed += (0..3).any(|c| (a[c] - b[c]).abs() > 30) as usize;
            }
        }
        let area = (W * (H - TOP_BAND - BOTTOM_BAND)) as usize;
        assert!(
            changed * 200 > area,
            "{}: only {changed} pixels changed between frames 0 and 120",
            scene.name
        );
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn the_egui_overlay_appears_when_asked_for() {
    let dir = out_dir("ui");
    let size = format!("{W}x{H}");
    for (file, ui) in [("plain.png", false), ("ui.png", true)] {
        let path = dir.join(file);
        std::fs::create_dir_all(&dir).unwrap();
        let mut args = vec!["--scene", "1", "--size", &size, "--out"];
        let p = path.to_str().unwrap().to_string();
        args.push(&p);
        if ui {
            args.push("--ui");
        }
        let out = capture(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let plain = Png::read(&dir.join("plain.png"));
    let ui = Png::read(&dir.join("ui.png"));
    // The panel is egui's dark theme (grey ~27) down the left edge; without --ui the same
    // strip is sky and ground (grey > 150). Mean brightness of x 20..120, y 60..300.
    let mean = |img: &Png| {
        let mut sum = 0i64;
        for y in 60..300 {
            for x in 20..120 {
                sum += img.px(x, y).iter().sum::<i32>() as i64 / 3;
            }
        }
        sum / (100 * 240)
    };
    let (m_plain, m_ui) = (mean(&plain), mean(&ui));
    assert!(
        m_plain > 120,
        "without --ui the strip is the scene: {m_plain}"
    );
    assert!(m_ui < 70, "with --ui the strip is the dark panel: {m_ui}");
    // The panel holds text: bright glyph pixels on the dark background.
    let bright = (60..300)
        .flat_map(|y| (20..120).map(move |x| (x, y)))
        .filter(|&(x, y)| ui.px(x, y).iter().all(|&c| c > 150))
        .count();
    assert!(bright > 50, "panel text pixels: {bright}");
}

#[test]
fn unwritable_output_and_missing_adapter_are_clear_errors() {
    let out = capture(&["--scene", "1", "--out", "/nonexistent-dir/frame.png"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent-dir/frame.png"), "{err}");

    // No backend this machine has: Metal exists only on Apple systems.
    let out = Command::new(env!("CARGO_BIN_EXE_ragdoll-lab"))
        .args(["capture", "--scene", "1", "--size", "64x36", "--out"])
        .arg(Path::new(env!("CARGO_TARGET_TMPDIR")).join("never.png"))
        .env("WGPU_BACKEND", "metal")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no graphics adapter"), "{err}");
}
