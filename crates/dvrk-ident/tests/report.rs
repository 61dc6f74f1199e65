//! Figures and the HTML report: valid SVG and PNG of the announced size with the
//! expected series, and a page that carries the numbers of the result it came from.
//!
//! Data: the bundled example log (`examples/psm_excitation.mcap`, in the repository),
//! first 4 s, fitted by OLS (fast) without filtering.

use std::path::PathBuf;

use dvrk_ident::excite::FourierTrajectory;
use dvrk_ident::report::draw::kinematic_drawing;
use dvrk_ident::report::plot::{render, Figure, ImageFormat, MAX_POINTS};
use dvrk_ident::report::{build, figures, ReportInput, ReportLog};
use dvrk_ident::validate::{joint_metrics, predict, prepare, JointMap};
use dvrk_ident::JointLog;
use dvrk_ident::Joints;
use dvrk_ident::Silent;
use dvrk_ident::{FitRequest, FitResult, FitSettings, Method};
use dvrk_model::Model;

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn example_log(seconds: f64) -> JointLog {
    let t = dvrk_ident::log::read(examples().join("psm_excitation.mcap"), None, None).unwrap();
    let t0 = t.time[0];
    let keep = t.time.iter().take_while(|&&s| s - t0 < seconds).count();
    let rows: Vec<usize> = (0..keep).collect();
    JointLog {
        time: t.time[..keep].to_vec(),
        q: t.q.select_rows(&rows),
        dq: t.dq.as_ref().map(|d| d.select_rows(&rows)),
        tau: t.tau.select_rows(&rows),
        ..t
    }
}

fn settings() -> FitSettings {
    let mut s = FitSettings {
        method: Method::Ols,
        ..FitSettings::default()
    };
    s.processing.filter = None;
    s
}

fn fitted() -> (Model, JointLog, FitResult) {
    let model = Model::builtin("psm").unwrap();
    let log = example_log(4.0);
    let result = FitRequest::of_samples([&log], Some(&log), settings())
        .run(Some(&model), &Silent)
        .unwrap()
        .result;
    (model, log, result)
}

/// Width and height attributes of an SVG document's root element.
fn svg_size(svg: &str) -> (u32, u32) {
    let root = &svg[svg.find("<svg").unwrap()..];
    let attr = |name: &str| -> u32 {
        let key = format!("{name}=\"");
        let s = &root[root.find(&key).unwrap() + key.len()..];
        s[..s.find('"').unwrap()].parse().unwrap()
    };
    (attr("width"), attr("height"))
}

/// Polylines drawn in colour `hex` (e.g. `#D62728`), with their point counts.
fn polylines(svg: &str, hex: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p[..p.find("/>").unwrap()].contains(&format!("stroke=\"{hex}\"")))
        .map(|p| {
            let s = &p[p.find("points=\"").unwrap() + 8..];
            s[..s.find('"').unwrap()].split_whitespace().count()
        })
        .collect()
}

fn png_size(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn torque_figure_has_one_panel_per_joint_with_three_series_and_units() {
    let (model, log, result) = fitted();
    let params = result.params_for(&model).unwrap();
    let data = prepare(&model, &log, &result.settings.processing).unwrap();
    let predicted = predict(&model, &params, &data);
    let joints = JointMap::new(&model, Joints::Model).unwrap();
    let metrics = joint_metrics(&model, &params, &data, None, &joints).unwrap();
    let zoom = figures::zoom_window(&data.time, &data.tau);
    let fig = figures::torque_figure(&joints, "training", &data, &predicted, &metrics, zoom);
    // Per coordinate the whole log, then its zoomed window.
    assert_eq!(fig.panels.len(), 14);
    // q3 is the PSM insertion (prismatic): newtons; the others newton-metres.
    assert_eq!(fig.panels[4].y_label, "torque (N)");
    assert_eq!(fig.panels[0].y_label, "torque (N·m)");
    let (a, b) = zoom;
    assert!(b > a && b <= data.len());
    for j in 0..7 {
        let (p, z) = (&fig.panels[2 * j], &fig.panels[2 * j + 1]);
        let labels: Vec<&str> = p.series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels, ["measured", "predicted", "measured − predicted"]);
        // The error series is measured minus predicted, sample by sample.
        for k in [0, data.len() / 2, data.len() - 1] {
            assert_eq!(p.series[2].y[k], data.tau[(k, j)] - predicted[(k, j)]);
        }
        assert!(p
            .title
            .contains(&format!("{:.4}", metrics.relative_error[j])));
        // The zoom is the window's samples, and the whole-log panel shades it.
        assert_eq!(z.series[0].y, p.series[0].y[a..b].to_vec());
        assert_eq!(p.vspans, [(p.series[0].x[a], p.series[0].x[b - 1])]);
    }

    let svg = String::from_utf8(render(&fig, ImageFormat::Svg).unwrap()).unwrap();
    assert_eq!(svg_size(&svg), fig.size());
    assert!(svg.trim_end().ends_with("</svg>"));
    // Per coordinate: the predicted curve with every sample (fewer than the panel keeps
    // here) and its zoom, plus one legend sample for the figure.
    let red = polylines(&svg, "#D62728");
    assert!(data.len() < MAX_POINTS);
    assert_eq!(
        red.iter().filter(|&&n| n == data.len()).count(),
        7,
        "{red:?}"
    );
    assert_eq!(red.iter().filter(|&&n| n == b - a).count(), 7, "{red:?}");
    assert_eq!(red.len(), 15);
    // One legend, above the panels (outside every chart).
    assert_eq!(svg.matches(">\nmeasured\n</text>").count(), 1);

    let png = render(&fig, ImageFormat::Png).unwrap();
    let (w, h, pixels) = png_size(&png);
    assert_eq!((w, h), fig.size());
    // Something was drawn in the predicted red (not only a white page).
    assert!(pixels
        .chunks(3)
        .any(|p| p[0] == 214 && p[1] == 39 && p[2] == 40));
}

#[test]
fn long_series_are_reduced_to_their_envelope() {
    let (model, log, result) = fitted();
    let params = result.params_for(&model).unwrap();
    // Upsample the example 4x to get more samples than the drawing keeps.
    let data = prepare(&model, &log, &result.settings.processing).unwrap();
    let mut long = data.clone();
    let reps = MAX_POINTS / data.len() + 2;
    let rows: Vec<usize> = (0..reps * data.len()).map(|k| k % data.len()).collect();
    long.q = data.q.select_rows(&rows);
    long.dq = data.dq.select_rows(&rows);
    long.ddq = data.ddq.select_rows(&rows);
    long.tau = data.tau.select_rows(&rows);
    long.time = (0..rows.len()).map(|k| k as f64 * 0.005).collect();
    let predicted = predict(&model, &params, &long);
    let joints = JointMap::new(&model, Joints::Model).unwrap();
    let metrics = joint_metrics(&model, &params, &long, None, &joints).unwrap();
    let zoom = figures::zoom_window(&long.time, &long.tau);
    let fig = figures::torque_figure(&joints, "long", &long, &predicted, &metrics, zoom);
    let svg = String::from_utf8(render(&fig, ImageFormat::Svg).unwrap()).unwrap();
    let red = polylines(&svg, "#D62728");
    let longest = *red.iter().max().unwrap();
    assert!(
        longest <= MAX_POINTS && longest > MAX_POINTS / 2,
        "{longest}"
    );
}

#[test]
fn report_page_carries_the_result_metrics_and_is_self_contained() {
    let (model, log, result) = fitted();
    let traj = FourierTrajectory::from_json_file(examples().join("psm_trajectory.json")).unwrap();
    let input = ReportInput {
        model: &model,
        result: &result,
        logs: vec![
            ReportLog {
                role: "training",
                trajectory: &log,
                window: None,
            },
            ReportLog {
                role: "test",
                trajectory: &log,
                window: Some(100),
            },
        ],
        excitation: Some(&traj),
        read: None,
        settings: None,
    };
    let report = build(&input).unwrap();
    let stems: Vec<&str> = report.figures.iter().map(|f| f.stem.as_str()).collect();
    assert_eq!(
        stems,
        [
            "torque_1_training",
            "processing_1_training",
            "friction_1_training",
            "residuals_1_training",
            "torque_2_test",
            "processing_2_test",
            "friction_2_test",
            "residuals_2_test",
            "base_parameters",
            "excitation",
            "kinematics"
        ]
    );
    let html = &report.html;
    for j in 0..7 {
        let rel = result.metrics.train.relative_error[j];
        assert!(html.contains(&format!("<td>{rel:.4}</td>")), "joint {j}");
    }
    // The recomputed training metrics are the result's (same data, same settings; the
    // fit takes them from its R factors, the report from the predictions: equal to
    // rounding); the windowed test ones use 100 samples.
    let (again, fitted) = (&report.logs[0].metrics, &result.metrics.train);
    assert_eq!(again.samples, fitted.samples);
    for (a, b) in again
        .relative_error
        .iter()
        .chain(&again.rms)
        .zip(fitted.relative_error.iter().chain(&fitted.rms))
    {
        assert!((a - b).abs() <= 1e-12 * b.abs(), "{again:?} vs {fitted:?}");
    }
    assert_eq!(report.logs[1].metrics.samples, 100);
    // Each metrics column once: the report's training log is the fit's training column,
    // its windowed test log a column of its own (the fit tested on the whole log).
    assert_eq!(html.matches("<th colspan=2>").count(), 3, "{html}");
    assert!(html.contains("fit: training, shown as training"));
    // The sections at the top, and the figures by id.
    let top = html.find("id=reproduce").unwrap();
    assert!(top < html.find("id=metrics").unwrap());
    assert!(html.contains("<pre id=command-line>dvrk-ident fit "));
    assert!(html.contains("<pre id=python-call>import dvrk_ident as di"));
    // The logs of this fit were samples, and how they were read is not known: said.
    assert!(html.contains("<ul id=not-reproduced>"));
    for stem in &stems {
        assert!(html.contains(&format!("<figure id=\"{stem}\">")), "{stem}");
    }
    for b in &result.base_parameters {
        assert!(html.contains(&dvrk_ident::report::html::escape(&b.expression)));
    }
    for l in &result.links {
        assert!(html.contains(&format!("<td class=l>{}</td>", l.link)));
        // The row's last cell says what the data determined, coloured as the result says.
        let at = html.find(&format!("<td class=l>{}</td>", l.link)).unwrap();
        let row = &html[at..at + html[at..].find("</tr>").unwrap()];
        let d = l.determined.unwrap();
        let class = |ok: bool| if ok { "ok" } else { "bad" };
        for (ok, what) in [(d.first_moment, "first moment"), (d.inertia, "inertia")] {
            let span = format!("<span class={}>{what}</span>", class(ok));
            assert!(row.contains(&span), "{}: {span} not in {row}", l.link);
        }
    }
    for (name, st) in &result.parameter_status {
        if name.starts_with('F') {
            let cell = format!(
                "<td class=l>{name}</td><td>{}</td><td class=l><span class={}>{}</span></td>",
                dvrk_ident::report::html::number(result.parameters[name]),
                if st.identified() { "ok" } else { "bad" },
                st.name().replace('_', " ")
            );
            assert!(html.contains(&cell), "{cell}");
        }
    }
    // Every figure inlined as SVG, nothing fetched from elsewhere.
    assert_eq!(html.matches("<svg").count(), report.figures.len());
    assert!(!html.contains("<script") && !html.contains("<link") && !html.contains("src="));
    assert!(!html.contains("href=\"http"));

    let dir = dvrk_test_support::temp_dir("dvrk-report");
    let written = report.write(&dir).unwrap();
    assert_eq!(written.len(), 2 * report.figures.len() + 1);
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names.len(),
        written.len(),
        "no temporary file left: {names:?}"
    );
    let back = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert_eq!(&back, html);
    let (w, h, _) = png_size(&std::fs::read(dir.join("kinematics.png")).unwrap());
    assert!(w > 600 && h > 600);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn excitation_figure_shows_limits_and_combinations() {
    let model = Model::builtin("psm").unwrap();
    let traj = FourierTrajectory::from_json_file(examples().join("psm_trajectory.json")).unwrap();
    let fig = figures::excitation_figure(&model, &traj, &model.limits, 100.0);
    let single = model
        .limits
        .iter()
        .filter(|l| l.position.is_some() && l.expr.terms.len() == 1 && l.expr.terms[0].1 == 1.0)
        .count();
    let combined = model.limits.iter().filter(|l| l.position.is_some()).count() - single;
    assert!(
        combined >= 1,
        "the PSM jaw limit is a combination of q6 and q7"
    );
    assert_eq!(fig.panels.len(), 7 + combined);
    let hlines: usize = fig.panels.iter().map(|p| p.hlines.len()).sum();
    assert_eq!(hlines, 2 * (single + combined));
    // The curve is the trajectory itself over one period.
    let (q, _, _) = traj.sample(&[0.0]);
    assert_eq!(fig.panels[1].series[0].y[0], q[(0, 1)]);
    let last = fig.panels[0].series[0].x.last().copied().unwrap();
    assert!((last - traj.period_s()).abs() < 1e-12);
}

#[test]
fn kinematic_drawing_flags_closed_chain_frames_and_draws_every_frame() {
    let model = Model::builtin("psm").unwrap();
    let q = [0.3, -0.2, 0.12, 0.1, 0.2, 0.0, 0.1];
    let d = kinematic_drawing(&model, &q).unwrap();
    let poses = model.frame_poses(&q);
    for (f, p) in d.frames.iter().zip(&poses) {
        assert_eq!(f.pose, *p);
    }
    let branch: Vec<&str> = d
        .frames
        .iter()
        .filter(|f| f.branch)
        .map(|f| f.name.as_str())
        .collect();
    let chain: Vec<&str> = d
        .frames
        .iter()
        .filter(|f| !f.branch)
        .map(|f| f.name.as_str())
        .collect();
    // In the 2019 PSM tree the tool hangs from the parallelogram's far end
    // (pitch_end); the parallelogram's other links, the insertion stage carried by the
    // pitch frame, the virtual motor frames and the two jaws (beside the wrist yaw, the
    // jaws' mean, that carries the tool tip) are branches.
    assert_eq!(
        chain,
        [
            "base",
            "yaw",
            "pitch_intermediate",
            "pitch_back",
            "pitch_front",
            "pitch_bottom",
            "pitch_end",
            "tool_roll",
            "wrist_pitch",
            "wrist_yaw",
            "tool_tip"
        ]
    );
    assert!(branch.contains(&"wrist_yaw_1") && branch.contains(&"wrist_yaw_2"));
    assert!(branch.contains(&"pitch_top") && branch.contains(&"main_insertion"));
    assert!(branch.contains(&"motor_6") && branch.contains(&"pitch_front_ext"));
    let svg = String::from_utf8(render(&d, ImageFormat::Svg).unwrap()).unwrap();
    assert_eq!(svg_size(&svg), d.size());
    // One origin marker per frame in each of the two views.
    assert_eq!(svg.matches("<circle").count(), 2 * d.frames.len());
    assert!(kinematic_drawing(&model, &[0.0; 3]).is_err());
    assert!(kinematic_drawing(&model, &[f64::NAN; 7]).is_err());
}

/// The friction curve of a simulated log whose friction is known: for every coordinate
/// moved by one friction element alone (the PSM's yaw, pitch, insertion and roll), each
/// bin's median of the measured torque minus the model without friction lies on the
/// true law `Fc·sign(v) + Fv·v + Fo` at the bin's median velocity within what the
/// torque noise allows, and so does the model's friction curve. The log: the bundled
/// example's parameters and trajectory, four periods at 200 Hz with white torque noise.
#[test]
fn friction_curve_of_a_simulated_log_lies_on_the_true_friction_law() {
    use dvrk_ident::report::curves::{friction_curves, MIN_BIN_SAMPLES};
    use dvrk_ident::simulate::{simulate, Simulation};

    let model = Model::builtin("psm").unwrap();
    let truth = dvrk_test_support::fixtures::example_params(&model);
    let traj = FourierTrajectory::from_json_file(examples().join("psm_trajectory.json")).unwrap();
    let sigma = 0.002;
    let sim = Simulation {
        duration_s: Some(4.0 * traj.period_s()),
        noise_std: vec![sigma],
        seed: 11,
        ..Simulation::default()
    };
    let log = simulate(&model, &truth, &traj, &sim).unwrap();
    let mut processing = settings().processing;
    processing.filter = None;
    let data = prepare(&model, &log, &processing).unwrap();
    let curves = friction_curves(
        &model,
        &truth,
        &data,
        &JointMap::new(&model, Joints::Model).unwrap(),
    );
    assert_eq!(curves.len(), model.dof());

    // Coordinates whose friction is one frame's, on `s = c·q_j`.
    let value = |name: &str| truth[model.param_index(name).unwrap()];
    let mut checked = Vec::new();
    for (j, curve) in curves.iter().enumerate() {
        let frames: Vec<(usize, f64)> = model
            .frames
            .iter()
            .enumerate()
            .filter(|(_, f)| f.friction().is_some())
            .filter_map(|(i, f)| {
                f.value
                    .terms
                    .iter()
                    .find(|&&(c, _)| c == j)
                    .map(|&(_, a)| (i + 1, a * f64::from(u8::from(f.value.terms.len() == 1))))
            })
            .collect();
        let [(frame, c)] = frames[..] else { continue };
        if c == 0.0 {
            continue;
        }
        let (fc, fv, fo) = (
            value(&format!("Fc{frame}")),
            value(&format!("Fv{frame}")),
            value(&format!("Fo{frame}")),
        );
        let law = |v: f64| {
            let s = c * v;
            c * (fc * s.signum() * f64::from(u8::from(s != 0.0)) + fv * s + fo)
        };
        assert!(
            curve.bins.len() >= 15,
            "{}: {} bins",
            curve.coordinate,
            curve.bins.len()
        );
        let mut worst: f64 = 0.0;
        for b in &curve.bins {
            assert!(b.count >= MIN_BIN_SAMPLES);
            // Standard error of a median of n samples of spread s: 1.2533 s / √n, where
            // s is the noise's σ and the law's own spread across the bin (it varies by
            // Fv·c²·width there, a uniform spread of that width has σ = width / √12).
            let slope = (fv * c * c).abs() * (b.edges.1 - b.edges.0);
            let spread = (sigma * sigma + slope * slope / 12.0).sqrt();
            let noise = 1.2533 * spread / (b.count as f64).sqrt();
            let error = (b.measured.median - law(b.x)).abs();
            assert!(
                error <= 5.0 * noise,
                "{} bin at {:.4}: median {:.5}, law {:.5}, {} samples",
                curve.coordinate,
                b.x,
                b.measured.median,
                law(b.x),
                b.count
            );
            worst = worst.max(error / noise);
            // The model's friction is the law itself, monotone within the bin: its median
            // is the law at the median velocity.
            let model_error = (b.model.unwrap() - law(b.x)).abs();
            assert!(model_error <= 1e-12, "{}: {model_error}", curve.coordinate);
            // The spread is the noise's: quartiles about 0.674 σ either side.
            assert!(b.measured.upper - b.measured.lower < 4.0 * sigma + slope);
        }
        checked.push((curve.coordinate.clone(), worst));
    }
    let names: Vec<&str> = checked.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["q1", "q2", "q3", "q4"], "{checked:?}");
    eprintln!("largest |median − law| / its standard error: {checked:?}");
}
