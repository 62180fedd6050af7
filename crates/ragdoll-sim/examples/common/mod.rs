//! What the lab humanoid's examples (`ensemble`, `energy_trace`) share: the figure and
//! the `--schedule` option.

use ragdoll_sim::SceneDesc;
use ragdoll_sim::scene::af::{AfOptions, load_character};
use ragdoll_sim::scene::decl::Doom3Base;
use std::path::PathBuf;

/// The humanoid of our Doom 3-style mod (assets/doom3, entity `monster_lab_human`),
/// built from its entity's `af_pose` frame as the engine builds it.
pub fn lab_human() -> Result<SceneDesc, String> {
    let base_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../assets/doom3");
    let base = Doom3Base::open(&base_dir).map_err(|e| e.to_string())?;
    let c = base
        .character("Monster_Lab_Human")
        .map_err(|e| e.to_string())?;
    load_character(&c, &base_dir, &AfOptions::default())
        .map(|s| s.desc)
        .map_err(|e| e.to_string())
}

/// The XPBD schedule `--schedule SxP` asks for (S substeps of P passes,
/// `Settings::xpbd_substeps`, `Settings::xpbd_passes`), `None` without the option.
pub fn xpbd_schedule(args: &[String]) -> Result<Option<(u32, u32)>, String> {
    let Some(at) = args.iter().position(|a| a == "--schedule") else {
        return Ok(None);
    };
    args.get(at + 1)
        .and_then(|v| v.split_once('x'))
        .and_then(|(s, p)| Some((s.parse().ok()?, p.parse().ok()?)))
        .map(Some)
        .ok_or_else(|| "--schedule takes substeps x passes, such as 60x1".to_string())
}

/// Sets `sc`'s XPBD schedule to `schedule` (see [`xpbd_schedule`]), if one is given.
pub fn set_xpbd_schedule(sc: &mut SceneDesc, schedule: Option<(u32, u32)>) {
    if let Some((substeps, passes)) = schedule {
        sc.settings.xpbd_substeps = Some(substeps);
        sc.settings.xpbd_passes = passes;
    }
}
