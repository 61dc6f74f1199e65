//! The self-contained `report.html`: tables of a result and its figures inlined as SVG,
//! so the page opens in a browser with no network and no other file.

use std::fmt::Write as _;

use dvrk_model::{Model, ParamKind};

use super::document::LogSummary;
use super::plot::RenderedFigure;
use crate::fit::JointMap;
use crate::log::ReadOptions;
use crate::reproduce::FitCall;
use crate::result::{FitResult, JointMetrics, LinkResult, ParameterStatus};
use crate::settings::Difference;

/// Escapes text for HTML element content and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// A number for a table: fixed notation in the readable range, scientific outside,
/// 6 significant digits either way (the JSON result keeps every digit).
pub fn number(v: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if a == 0.0 || (1e-3..1e5).contains(&a) {
        let digits = if a == 0.0 {
            0
        } else {
            (5 - a.log10().floor() as i32).clamp(0, 9) as usize
        };
        format!("{v:.digits$}")
    } else {
        format!("{v:.5e}")
    }
}

pub(crate) const STYLE: &str = "body{font-family:'DejaVu Sans',Arial,sans-serif;margin:24px;color:#222;max-width:1400px}\
h1{font-size:24px}h2{font-size:19px;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:32px}\
table{border-collapse:collapse;margin:8px 0;font-size:13px}\
th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}\
th{background:#f2f2f2}td.l,th.l{text-align:left}\
.bad{color:#b00020;font-weight:bold}.ok{color:#106010}\
figure{margin:16px 0}figcaption{font-size:13px;color:#555}\
figure svg{max-width:100%;height:auto}pre{background:#f7f7f7;padding:8px;font-size:12px;overflow:auto}";

/// One table, the metrics of every set side by side (the fit's training and test
/// logs, then the logs of this report), so held-out errors read against the fitted
/// ones joint by joint.
fn metrics_table(
    out: &mut String,
    sets: &[(String, &JointMetrics)],
    unit: &dyn Fn(usize) -> &'static str,
) {
    out.push_str("<table><tr><th class=l rowspan=2>joint</th>");
    for (caption, m) in sets {
        let _ = write!(
            out,
            "<th colspan=2>{} ({} samples)</th>",
            escape(caption),
            m.samples
        );
    }
    out.push_str("<th class=l rowspan=2>unit</th></tr><tr>");
    for _ in sets {
        out.push_str("<th>relative error</th><th>RMS</th>");
    }
    out.push_str("</tr>");
    let joints = sets.first().map_or(&[][..], |(_, m)| &m.joints[..]);
    for (j, name) in joints.iter().enumerate() {
        let _ = write!(out, "<tr><td class=l>{}</td>", escape(name));
        for (_, m) in sets {
            let _ = write!(
                out,
                "<td>{:.4}</td><td>{}</td>",
                m.relative_error.get(j).copied().unwrap_or(f64::NAN),
                number(m.rms.get(j).copied().unwrap_or(f64::NAN)),
            );
        }
        let _ = write!(out, "<td class=l>{}</td></tr>", unit(j));
    }
    out.push_str("</table>");
}

/// The SVG document without an XML prolog, ready to inline.
pub(crate) fn inline_svg(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

/// How the logs of a page are shown: their joints, and the settings that differ from
/// the result's.
pub struct Shown<'a> {
    /// The joints of the logs' metrics and figures.
    pub joints: &'a JointMap,
    /// The settings of the logs that differ from the fit's
    /// ([`crate::FitSettings::differences`]).
    pub differences: &'a [Difference],
}

/// Says which settings the logs drawn here are processed or shown with other than the
/// fit's, so that a figure is not read as the fit's own processing.
fn shown_settings(o: &mut String, differences: &[Difference]) {
    if differences.is_empty() {
        return;
    }
    o.push_str(
        "<p>The logs drawn here are processed and shown with settings that differ from the \
         fit's (the fit's columns, command line and settings are its own):</p><table>\
         <tr><th class=l>setting</th><th class=l>here</th><th class=l>fit</th></tr>",
    );
    for d in differences {
        let (here, fit) = d.shown();
        let _ = write!(
            o,
            "<tr><td class=l>{}</td><td class=l>{}</td><td class=l>{}</td></tr>",
            escape(&d.path),
            escape(&here),
            escape(&fit)
        );
    }
    o.push_str("</table>");
}

/// The whole page.
pub fn page(
    model: &Model,
    result: &FitResult,
    shown: &Shown<'_>,
    logs: &[LogSummary],
    figures: &[RenderedFigure],
    read: Option<&ReadOptions>,
) -> String {
    // The fit's own metrics are in the joints of its settings; the logs' in those shown.
    let joints = shown.joints;
    let fit_joints = JointMap::new(model, result.settings.joints).unwrap_or(joints.clone());
    let fit_unit = |j: usize| fit_joints.units(j)[3];
    let log_unit = |j: usize| joints.units(j)[3];
    let mut o = String::new();
    let _ = write!(
        o,
        "<!DOCTYPE html><html lang=en><head><meta charset=utf-8>\
         <title>dvrk-ident report: {robot} ({method})</title><style>{STYLE}</style></head><body>\
         <h1>Identification report: {robot}, {method}</h1>",
        robot = escape(&result.robot),
        method = escape(&result.method)
    );

    reproduce(&mut o, result, read);
    contents(&mut o, figures);
    summary(&mut o, result);
    metrics(&mut o, result, logs, &fit_unit, &log_unit);
    shown_settings(&mut o, shown.differences);
    links(&mut o, result);
    joint_elements(&mut o, model, result);
    base_parameters(&mut o, result);
    figures_section(&mut o, figures);
    settings_and_provenance(&mut o, result);
    o.push_str("</body></html>\n");
    o
}

/// Summary and solver.
fn summary(o: &mut String, result: &FitResult) {
    let consistent = if result.physically_consistent {
        "<span class=ok>yes</span>"
    } else {
        "<span class=bad>no</span>"
    };
    let converged = if result.solver.converged {
        "<span class=ok>converged</span>"
    } else {
        "<span class=bad>NOT converged: these numbers are not a result</span>"
    };
    let _ = write!(
        o,
        "<h2>Summary</h2><table>\
         <tr><th class=l>robot</th><td class=l>{} ({})</td></tr>\
         <tr><th class=l>method</th><td class=l>{}</td></tr>\
         <tr><th class=l>solver</th><td class=l>{} — {} — {} ({} iterations, {:.3} s)</td></tr>\
         <tr><th class=l>physically consistent</th><td class=l>{}</td></tr>\
         <tr><th class=l>observation rows</th><td class=l>{}</td></tr>\
         <tr><th class=l>condition number</th><td class=l>{}</td></tr>\
         <tr><th class=l>residual variance σ²</th><td class=l>{}</td></tr>\
         <tr><th class=l>tool</th><td class=l>{}</td></tr>",
        escape(&result.robot),
        escape(&result.robot_source),
        escape(&result.method),
        escape(&result.solver.name),
        result.solver.status,
        converged,
        result.solver.iterations,
        result.solver.seconds,
        consistent,
        result.rows,
        number(result.condition_number),
        number(result.sigma2),
        escape(&result.tool),
    );
    let delays = &result.settings.processing.delay_s;
    if !delays.is_empty() {
        let how = if result.delay.is_some() {
            "estimated"
        } else {
            "given"
        };
        let ms: Vec<String> = delays.iter().map(|d| format!("{:.1}", d * 1e3)).collect();
        let _ = write!(
            o,
            "<tr><th class=l>torque delays ({how}, ms)</th><td class=l>{}</td></tr>",
            ms.join(" ")
        );
    }
    if let Some(sel) = &result.selection {
        let rows: Vec<String> = sel
            .candidates
            .iter()
            .map(|c| {
                let mark = if c.candidate == sel.chosen {
                    " (chosen)"
                } else {
                    ""
                };
                let per: Vec<String> = c.relative_error.iter().map(|e| format!("{e:.4}")).collect();
                format!(
                    "{}{mark}: mean {:.4} [{}]",
                    escape(&c.candidate),
                    c.mean,
                    per.join(" ")
                )
            })
            .collect();
        let _ = write!(
            o,
            "<tr><th class=l>friction model by held-out error ({})</th><td class=l>{}</td></tr>",
            sel.folds.describe(),
            rows.join("<br>")
        );
    }
    for i in result.inputs.iter().filter(|i| i.offset.is_some()) {
        let values: Vec<String> = i
            .offset
            .iter()
            .flatten()
            .map(|v| format!("{v:+.4}"))
            .collect();
        let _ = write!(
            o,
            "<tr><th class=l>own torque offset of {} (over the model's)</th><td class=l>{}</td></tr>",
            escape(if i.path.is_empty() { &i.source } else { &i.path }),
            values.join(" ")
        );
    }
    if let Some(p) = &result.settings.prior {
        let divergence = result.prior_divergence.map_or(String::new(), |d| {
            format!(", divergence from it {}", number(d))
        });
        let _ = write!(
            o,
            "<tr><th class=l>prior</th><td class=l>{} ({} metric, weight {}){}</td></tr>",
            escape(&p.source),
            p.metric.name(),
            p.weight,
            divergence
        );
    }
    o.push_str("</table>");
}

/// The command line and the Python call that repeat the fit, and what they cannot
/// repeat.
fn reproduce(o: &mut String, result: &FitResult, read: Option<&ReadOptions>) {
    let call = FitCall::of_result(result, read);
    let (cli, py) = (call.cli_command(), call.python_call());
    let _ = write!(
        o,
        "<section id=reproduce><h2>Reproduce</h2><p>The command line that repeats this fit \
         (add <code>--out result.json --report DIR</code> for the files):</p>\
         <pre id=command-line>{}</pre><p>The same fit from Python:</p>\
         <pre id=python-call>{}</pre>",
        escape(&cli.text),
        escape(py.text.trim_end())
    );
    let mut notes: Vec<(&str, &String)> = Vec::new();
    for n in &cli.unrendered {
        let front = if py.unrendered.contains(n) {
            "command line and Python"
        } else {
            "command line (Python passes it in settings=)"
        };
        notes.push((front, n));
    }
    for n in py.unrendered.iter().filter(|n| !cli.unrendered.contains(n)) {
        notes.push(("Python", n));
    }
    if !notes.is_empty() {
        o.push_str("<p>Not repeated by the text above:</p><ul id=not-reproduced>");
        for (front, n) in notes {
            let _ = write!(o, "<li>{}: {}</li>", front, escape(n));
        }
        o.push_str("</ul>");
    }
    o.push_str("</section>");
}

/// Links to the sections and figures of the page.
fn contents(o: &mut String, figures: &[RenderedFigure]) {
    o.push_str(
        "<nav id=contents><b>Contents</b>: <a href=\"#reproduce\">reproduce</a> · \
         <a href=\"#metrics\">metrics</a> · <a href=\"#links\">links</a> · \
         <a href=\"#joint-elements\">joint elements</a> · \
         <a href=\"#base-parameters\">base parameters</a> · figures:",
    );
    for f in figures {
        let _ = write!(o, " <a href=\"#{stem}\">{stem}</a>", stem = escape(&f.stem));
    }
    o.push_str(" · <a href=\"#settings\">settings</a></nav>");
}

/// Whether two metric sets are the same numbers (same samples; every error equal to
/// rounding): the report's recomputation of a log the fit already measured.
fn same_metrics(a: &JointMetrics, b: &JointMetrics) -> bool {
    let close = |x: &[f64], y: &[f64]| {
        x.len() == y.len()
            && x.iter()
                .zip(y)
                .all(|(p, q)| (p - q).abs() <= 1e-9 * p.abs().max(q.abs()) || p == q)
    };
    a.samples == b.samples
        && a.joints == b.joints
        && close(&a.relative_error, &b.relative_error)
        && close(&a.rms, &b.rms)
}

/// Metrics of the result, then of every log drawn here whose numbers are not already a
/// column (each column once: a log the fit measured names the fit's column instead).
/// Logs shown in other joints than the fit's metrics get a table of their own.
fn metrics(
    o: &mut String,
    result: &FitResult,
    logs: &[LogSummary],
    fit_unit: &dyn Fn(usize) -> &'static str,
    log_unit: &dyn Fn(usize) -> &'static str,
) {
    o.push_str("<h2 id=metrics>Metrics</h2><p>Relative error ‖τ − τ̂‖/‖τ‖ and RMS of τ − τ̂ per joint (the model coordinates, or the arm's measured joints with joints measured; known forces subtracted).</p>");
    let mut sets: Vec<(String, &JointMetrics)> =
        vec![("fit: training".to_string(), &result.metrics.train)];
    if let Some(test) = &result.metrics.test {
        sets.push(("fit: test".to_string(), test));
    }
    let fitted = sets.len();
    let mut other_joints: Vec<(String, &JointMetrics)> = Vec::new();
    for log in logs {
        let name = format!("{} ({})", log.role, log.source);
        if log.metrics.joints != result.metrics.train.joints {
            other_joints.push((name, &log.metrics));
            continue;
        }
        match sets[..fitted]
            .iter_mut()
            .find(|(_, m)| same_metrics(m, &log.metrics))
        {
            Some((caption, _)) => {
                let _ = write!(caption, ", shown as {name}");
            }
            None => sets.push((name, &log.metrics)),
        }
    }
    metrics_table(o, &sets, fit_unit);
    if !other_joints.is_empty() {
        o.push_str("<p>The logs drawn here, in the joints of the figures:</p>");
        metrics_table(o, &other_joints, log_unit);
    }
}

/// Parameters by link.
fn links(o: &mut String, result: &FitResult) {
    o.push_str(
        "<h2 id=links>Links</h2><p>Standard parameters in each link's frame: mass (kg), centre of mass (m), \
         inertia about the centre of mass (kg·m²); consistency is the smallest eigenvalue of the \
         4×4 pseudo-inertia (kg·m², positive: realizable by a positive mass density); \
         determined by the data: whether the data alone fix the mass, the first moment and \
         the inertia about the frame origin (in red when the bounds, the regularization or a \
         prior set them; the result's <code>parameter_status</code>).</p>\
         <table><tr><th>frame</th><th class=l>link</th><th>mass</th><th>cx</th><th>cy</th><th>cz</th>\
         <th>Ixx</th><th>Ixy</th><th>Ixz</th><th>Iyy</th><th>Iyz</th><th>Izz</th>\
         <th>min eigenvalue</th><th class=l>consistent</th><th class=l>determined by the data</th></tr>",
    );
    for link in &result.links {
        let c = result.consistency.iter().find(|c| c.frame == link.frame);
        let _ = write!(
            o,
            "<tr><td>{}</td><td class=l>{}</td><td>{}</td>",
            link.frame,
            escape(&link.link),
            number(link.mass)
        );
        for v in link.com.iter().chain(&link.inertia_com) {
            let _ = write!(o, "<td>{}</td>", number(*v));
        }
        match c {
            Some(c) => {
                let _ = write!(
                    o,
                    "<td>{}</td><td class=l>{}</td>",
                    number(c.min_eigenvalue),
                    if c.consistent {
                        "<span class=ok>yes</span>"
                    } else {
                        "<span class=bad>no</span>"
                    }
                );
            }
            None => o.push_str("<td></td><td></td>"),
        }
        let _ = write!(o, "<td class=l>{}</td></tr>", determined_cell(result, link));
    }
    o.push_str("</table>");
}

/// A link's mass, first moment and inertia, green when the data determined them, red
/// (with the bound, for the mass) when not; empty for a result without statuses.
fn determined_cell(result: &FitResult, link: &LinkResult) -> String {
    let (Some(d), Some(block)) = (link.determined, result.link_status(link)) else {
        return String::new();
    };
    let mass = match block[9].1 {
        ParameterStatus::AtLowerBound => "mass at its lower bound",
        ParameterStatus::AtUpperBound => "mass at its upper bound",
        _ => "mass",
    };
    [
        (d.mass, mass),
        (d.first_moment, "first moment"),
        (d.inertia, "inertia"),
    ]
    .iter()
    .map(|&(ok, what)| {
        format!(
            "<span class={}>{what}</span>",
            if ok { "ok" } else { "bad" }
        )
    })
    .collect::<Vec<_>>()
    .join(", ")
}

/// A parameter's status, red unless identified; empty without one.
fn status_cell(status: Option<&ParameterStatus>) -> String {
    match status {
        None => String::new(),
        Some(s) => format!(
            "<span class={}>{}</span>",
            if s.identified() { "ok" } else { "bad" },
            s.name().replace('_', " ")
        ),
    }
}

/// Joint elements (friction, motor inertia, spring) by frame.
fn joint_elements(o: &mut String, model: &Model, result: &FitResult) {
    o.push_str(
        "<h2 id=joint-elements>Joint elements</h2><p>Coulomb Fc, viscous Fv and offset Fo friction (N·m, N·m·s/rad; N, N·s/m), \
         motor inertia Im (kg·m²), spring K, by frame, with what the data determined of each \
         (the result's <code>parameter_status</code>).</p>\
         <table><tr><th>frame</th><th class=l>name</th><th class=l>parameter</th><th>value</th>\
         <th class=l>status</th></tr>",
    );
    for p in &model.params {
        if matches!(p.kind, ParamKind::Inertia { .. }) {
            continue;
        }
        let value = result.parameters.get(&p.name).copied().unwrap_or(f64::NAN);
        let _ = write!(
            o,
            "<tr><td>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td class=l>{}</td></tr>",
            p.frame,
            escape(&model.frames[p.frame - 1].name),
            escape(&p.name),
            number(value),
            status_cell(result.parameter_status.get(&p.name))
        );
    }
    o.push_str("</table>");
}

/// Base parameters.
fn base_parameters(o: &mut String, result: &FitResult) {
    let _ = write!(
        o,
        "<h2 id=base-parameters>Base parameters</h2><p>{} independent combinations the data \
         determine; std is the standard deviation of the least-squares fit of the same \
         weighted data; the expression is given when it is more than the name.</p>\
         <table><tr><th>#</th><th class=l>name</th><th class=l>expression</th><th>value</th>\
         <th>std</th><th>relative std (%)</th></tr>",
        result.base_parameters.len()
    );
    for (i, b) in result.base_parameters.iter().enumerate() {
        let _ = write!(
            o,
            "<tr><td>{}</td><td class=l>{}</td><td class=l>{}</td><td>{}</td><td>{}</td><td>{:.2}</td></tr>",
            i + 1,
            escape(&b.name),
            if b.expression == b.name {
                String::new()
            } else {
                escape(&b.expression)
            },
            number(b.value),
            number(b.std),
            100.0 * b.std / b.value.abs()
        );
    }
    o.push_str("</table>");
}

/// Figures.
fn figures_section(o: &mut String, figures: &[RenderedFigure]) {
    o.push_str("<h2>Figures</h2>");
    for f in figures {
        let _ = write!(
            o,
            "<figure id=\"{stem}\">{svg}<figcaption>{caption} Files: \
             <a href=\"{stem}.svg\">{stem}.svg</a>, <a href=\"{stem}.png\">{stem}.png</a>.\
             </figcaption></figure>",
            stem = escape(&f.stem),
            svg = inline_svg(&f.svg),
            caption = escape(&f.caption)
        );
    }
}

/// Settings and provenance.
fn settings_and_provenance(o: &mut String, result: &FitResult) {
    let settings = serde_json::to_string_pretty(&result.settings).unwrap_or_default();
    let _ = write!(
        o,
        "<h2 id=settings>Settings</h2><pre>{}</pre><p>Row weights per coordinate: {}</p>",
        escape(&settings),
        result
            .weights
            .iter()
            .map(|w| number(*w))
            .collect::<Vec<_>>()
            .join(", ")
    );
    o.push_str(
        "<h2>Provenance</h2><table><tr><th class=l>role</th><th class=l>path</th>\
         <th class=l>SHA-256</th><th>bytes</th></tr>",
    );
    for i in &result.inputs {
        let _ = write!(
            o,
            "<tr><td class=l>{}</td><td class=l>{}</td><td class=l><code>{}</code></td><td>{}</td></tr>",
            escape(&i.role),
            escape(&i.path),
            escape(&i.sha256),
            i.bytes
        );
    }
    o.push_str("</table>");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_formats_numbers() {
        assert_eq!(escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1.234_567_89), "1.23457");
        assert_eq!(number(-0.012_345_678), "-0.0123457");
        assert_eq!(number(1.5e-7), "1.50000e-7");
        assert_eq!(number(f64::NAN), "NaN");
    }
}
