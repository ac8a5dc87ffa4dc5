//! Every shipped example (`examples/*.toml`) runs warning-free, whole, on
//! its own settings: a newcomer's first runs show no warning to wonder
//! about. The scene reads without warnings; a dynamics scene integrates its
//! whole `[run] duration` with its energy balance inside a tenth of the
//! bound (the watch's warning threshold) and strains inside the model's
//! validity; a statics scene converges. (`softrod run` prints exactly these
//! warnings.)

use softrod::{Flow, Observer, Sample, Simulation};
use softrod_scene::Mode;

struct Discard;
impl Observer for Discard {
    fn sample(&mut self, _: Sample<'_>) -> Result<Flow, String> {
        Ok(Flow::Continue)
    }
}

#[test]
fn shipped_examples_run_whole_without_warnings() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    assert!(paths.len() >= 10, "{paths:?}");
    for p in paths {
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        let (mut sim, scene, warnings) =
            Simulation::from_scene_file(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        match scene.run.mode {
            Mode::Dynamics => {
                let sum = sim
                    .simulate_with(scene.run.duration, &mut Discard)
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                println!("{name}: {:?} {:?}", sum.energy, sum.stats);
                assert_eq!(sum.t_final, scene.run.duration, "{name}");
                assert!(sum.warnings.is_empty(), "{name}: {:?}", sum.warnings);
            }
            Mode::Statics => {
                let eq = sim.statics().unwrap_or_else(|e| panic!("{name}: {e}"));
                assert!(eq.residual.is_finite(), "{name}");
            }
        }
    }
}
