//! The output rules, tried on real files, links, devices and failures.

use super::*;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dvrk-ident-output-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn entries(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn symlink_is_written_through() {
    let d = dir("link");
    let target = d.join("target.json");
    std::fs::write(&target, "old").unwrap();
    let link = d.join("link.json");
    std::os::unix::fs::symlink("target.json", &link).unwrap();
    write_with(&link, |w| w.write_all(b"new")).unwrap();
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    assert_eq!(entries(&d), ["link.json", "target.json"]);
    // A dangling link creates the file it names.
    let dangling = d.join("dangling.json");
    std::os::unix::fs::symlink("made.json", &dangling).unwrap();
    write_with(&dangling, |w| w.write_all(b"made")).unwrap();
    assert_eq!(
        std::fs::read_to_string(d.join("made.json")).unwrap(),
        "made"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn device_is_written_in_place() {
    // /dev/null stays a character device.
    write_with(Path::new("/dev/null"), |w| w.write_all(b"x")).unwrap();
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    assert_eq!(
        Destination::of(Path::new("/dev/null")).unwrap(),
        Destination::Special("/dev/null".into())
    );
}

#[test]
fn missing_folder_is_refused_not_created() {
    let d = dir("missing");
    let out = d.join("no").join("such").join("file.json");
    let e = write_with(&out, |w| w.write_all(b"x")).unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    assert!(!d.join("no").exists());
    let e = Outputs::new()
        .add_dir(&d.join("no").join("report"), &[("a".into(), b"x")])
        .unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    assert!(entries(&d).is_empty());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn permissions_are_kept() {
    use std::os::unix::fs::PermissionsExt;
    let d = dir("mode");
    let f = d.join("f.txt");
    std::fs::write(&f, "old").unwrap();
    std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o600)).unwrap();
    write_with(&f, |w| w.write_all(b"new")).unwrap();
    assert_eq!(
        std::fs::metadata(&f).unwrap().permissions().mode() & 0o777,
        0o600
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn failed_staging_leaves_nothing() {
    let d = dir("staging");
    let mut outputs = Outputs::new();
    outputs.add(&d.join("a.json"), b"a").unwrap();
    outputs
        .add_dir(&d.join("report"), &[("r.html".into(), b"r")])
        .unwrap();
    let e = outputs.add(&d.join("a.json"), b"b").unwrap_err();
    assert!(e.to_string().contains("same destination"), "{e}");
    let e = outputs
        .add(&d.join("missing").join("b.json"), b"b")
        .unwrap_err();
    assert!(e.to_string().contains("does not exist"), "{e}");
    drop(outputs);
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_input_is_never_an_output() {
    let d = dir("inputs");
    let log = d.join("log.csv");
    std::fs::write(&log, "recording").unwrap();
    let mut inputs = Inputs::new();
    inputs.add_log(&log);
    inputs.add("the robot", Path::new("psm")); // a built-in name: no file, skipped
                                               // The same file under every spelling: itself, through `..`, a symbolic link, a
                                               // hard link.
    std::fs::create_dir(d.join("sub")).unwrap();
    std::os::unix::fs::symlink("log.csv", d.join("link.csv")).unwrap();
    std::fs::hard_link(&log, d.join("hard.csv")).unwrap();
    for same in [
        log.clone(),
        d.join("sub").join("..").join("log.csv"),
        d.join("link.csv"),
        d.join("hard.csv"),
    ] {
        let e = inputs.check(&same).unwrap_err().to_string();
        assert!(
            e.contains("the same file as the log") && e.contains("log.csv"),
            "{e}"
        );
        let mut outputs = Outputs::protecting(inputs.clone());
        let e = outputs.add(&same, b"json").unwrap_err().to_string();
        assert!(e.contains("an output never replaces an input"), "{e}");
        drop(outputs);
    }
    // Another file, a new file and standard output are outputs.
    std::fs::write(d.join("other.json"), "old").unwrap();
    for other in ["other.json", "new.json", "-"] {
        let p = if other == "-" {
            PathBuf::from("-")
        } else {
            d.join(other)
        };
        inputs.check(&p).unwrap();
    }
    // A report folder may not be an input folder; a file in it that is an input is
    // refused when staged.
    let mut folder = Inputs::new();
    folder.add("the folder", &d.join("sub"));
    folder.add("the log", &log);
    let mut outputs = Outputs::protecting(folder);
    assert!(outputs
        .add_dir(&d.join("sub"), &[("r.html".into(), b"r")])
        .is_err());
    let e = outputs
        .add_dir(&d, &[("log.csv".into(), b"r")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("the same file as the log"), "{e}");
    drop(outputs);
    assert_eq!(std::fs::read_to_string(&log).unwrap(), "recording");
    assert_eq!(
        entries(&d),
        ["hard.csv", "link.csv", "log.csv", "other.json", "sub"]
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn commit_puts_everything_in_place() {
    let d = dir("commit");
    std::fs::create_dir(d.join("existing")).unwrap();
    std::fs::write(d.join("existing").join("old.txt"), "kept").unwrap();
    let mut outputs = Outputs::new();
    outputs.add(&d.join("a.json"), b"a").unwrap();
    let files = outputs
        .add_dir(&d.join("report"), &[("r.html".into(), b"r")])
        .unwrap();
    outputs
        .add_dir(&d.join("existing"), &[("new.txt".into(), b"n")])
        .unwrap();
    outputs.add(Path::new("/dev/null"), b"x").unwrap();
    outputs.commit().unwrap();
    assert_eq!(files, [d.join("report").join("r.html")]);
    assert_eq!(entries(&d), ["a.json", "existing", "report"]);
    assert_eq!(entries(&d.join("existing")), ["new.txt", "old.txt"]);
    assert_eq!(std::fs::read_to_string(&files[0]).unwrap(), "r");
    std::fs::remove_dir_all(&d).unwrap();
}
