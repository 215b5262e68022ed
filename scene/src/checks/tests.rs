use crate::{Scene, DEFAULT_SCENE};

fn with(from: &str, to: &str) -> Result<Scene, String> {
    assert!(DEFAULT_SCENE.contains(from), "{from}");
    Scene::parse(&DEFAULT_SCENE.replacen(from, to, 1), "s.toml").map_err(|e| e.to_string())
}

/// A name that is not a plain file name would put the outputs elsewhere (`out/..` is the
/// parent of out/): refused naming the field.
#[test]
fn a_name_that_is_not_a_plain_file_name_is_refused() {
    for bad in ["", ".", "..", "a/b", "../x", "a\\\\b", "a\\u0000b"] {
        let e = with("name = \"default\"", &format!("name = \"{bad}\"")).expect_err(bad);
        assert!(e.starts_with("s.toml: name = "), "{bad}: {e}");
        assert!(e.contains("(it names output folders)"), "{bad}: {e}");
    }
    for good in ["a", "a.b", "...", "run-1_b"] {
        let scene = with("name = \"default\"", &format!("name = \"{good}\""));
        assert_eq!(scene.map(|s| s.name), Ok(good.to_string()));
    }
}

/// A solid box that makes no cell solid (wholly outside the domain, or between the cell
/// centres) and a DEM box wholly outside the domain are accepted with a warning naming them.
#[test]
fn a_box_that_does_nothing_warns() {
    let boxes = "check_interval = 100\n\
                 [[lattice.solid_box]]\nmin = [0.0, 0.0, 0.0]\nmax = [0.032, 0.032, 0.002]\n\
                 [[lattice.solid_box]]\nmin = [0.1, 0.0, 0.0]\nmax = [0.2, 0.032, 0.002]\n\
                 [[lattice.solid_box]]\nmin = [0.0, 0.0, 0.0029]\nmax = [0.032, 0.032, 0.0034]\n";
    let scene = with("check_interval = 100", boxes).expect("a warning, not an error");
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0]
            .starts_with("s.toml: lattice.solid_box[1] = min [0.1, 0, 0] m, max [0.2, 0.032, 0.002] m: ")
            && scene.warnings[0].contains("wholly outside the domain"),
        "{}",
        scene.warnings[0]
    );
    assert!(
        scene.warnings[1].starts_with("s.toml: lattice.solid_box[2] = ")
            && scene.warnings[1].contains("no cell centre"),
        "{}",
        scene.warnings[1]
    );
    let dem_box = "[[dem.box]]\nmin = [0.0, 0.0, 1.0]\nmax = [0.032, 0.032, 2.0]\ninside = false\n\
                   [[dem.insert]]";
    let scene = with("[[dem.insert]]", dem_box).expect("a warning, not an error");
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].starts_with("s.toml: dem.box[0] = ")
            && scene.warnings[0].contains("wholly outside the domain"),
        "{}",
        scene.warnings[0]
    );
    assert!(
        with("name", "name").unwrap().warnings.is_empty(),
        "the default scene warns"
    );
}
