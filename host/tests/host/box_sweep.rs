//! Sweeps vary the periodic box: `"box.size"` as a sweep key
//! reaches each point's `[box]`, and a size the box refuses is an error at the sweep
//! value's line. (An integration test, so the sweep module stays as it is.)

use std::path::Path;

use hydrorattle_host::scene::BoxMethod;
use hydrorattle_host::sweep::Sweep;

const CHAIN: &str = include_str!("../../scenes/periodic_chain.toml");

#[test]
fn the_box_size_is_a_sweep_key() {
    let text = format!(
        "{CHAIN}\n[sweep]\n\"box.size\" = [[16.0, 16.0, 24.0], [20.0, 20.0, 20.0]]\n\"box.method\" = [\"ewald\", \"auto\"]\n"
    );
    let s = Sweep::parse(&text, "s.toml", Path::new(".")).unwrap();
    assert_eq!(s.keys, ["box.size", "box.method"]);
    let got: Vec<([f64; 3], BoxMethod)> = s
        .points
        .iter()
        .map(|p| {
            let b = p.scene.periodic.unwrap();
            (b.size, b.method)
        })
        .collect();
    let (a, b) = ([16.0, 16.0, 24.0], [20.0; 3]);
    let want = [
        (a, BoxMethod::Ewald),
        (a, BoxMethod::Auto),
        (b, BoxMethod::Ewald),
        (b, BoxMethod::Auto),
    ];
    assert_eq!(got, want);
    // The state point holds the box as the sweep gave it.
    let sp = &s.points[2].statepoint;
    assert_eq!(sp["box"]["size"], serde_json::json!([20.0, 20.0, 20.0]));
}

#[test]
fn a_box_the_scene_refuses_is_an_error_at_the_sweep_value() {
    let text =
        format!("{CHAIN}\n[sweep]\n\"box.size\" = [[16.0, 16.0, 24.0],\n [16.0, -1.0, 24.0]]\n");
    let e = Sweep::parse(&text, "s.toml", Path::new(".")).unwrap_err();
    let line = text.lines().position(|l| l.contains("-1.0")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{e}");
    assert!(
        e.message.contains("every edge must be finite and > 0"),
        "{e}"
    );
    // A box too small for the chain's head (radius 2): refused at the value too.
    let text = format!("{CHAIN}\n[sweep]\n\"box.size\" = [[3.5, 16.0, 24.0]]\n");
    let e = Sweep::parse(&text, "s.toml", Path::new(".")).unwrap_err();
    let line = text.lines().position(|l| l.contains("3.5")).unwrap() + 1;
    assert_eq!(e.line(), Some(line), "{e}");
}
