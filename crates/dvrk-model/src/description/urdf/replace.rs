//! Replace mode ([`Model::urdf_with_inertials`]): the URDF a model was imported from,
//! with the `<inertial>` of every identified link replaced and nothing else touched. It
//! splices the text at the byte spans `quick-xml` reports, because a round trip through
//! `urdf-rs`'s types would drop what they do not model (comments, `<transmission>`,
//! `<gazebo>`, `<ros2_control>`, the element order). The import
//! ([`Model::from_urdf_str`]) makes every model frame the URDF frame of the joint's child
//! link (`pre·post` is the joint origin, the motion is about the normalized axis), so the
//! identified values go in unchanged: mass, centre of mass as the inertial origin, the
//! inertia about it in the link axes, rpy zero.

use std::collections::{HashMap, HashSet};

use serde::Serialize;

use super::inertials::urdf_inertial;
use crate::error::ModelError;
use crate::model::*;

/// The leading whitespace of the line containing `pos`.
fn line_indent(text: &str, pos: usize) -> &str {
    let line = &text[text[..pos].rfind('\n').map_or(0, |k| k + 1)..];
    &line[..line.len() - line.trim_start_matches([' ', '\t']).len()]
}

/// The indentation of an element starting at `pos`: its line's, or one level deeper when
/// it starts after other markup on that line.
fn element_indent(text: &str, pos: usize) -> String {
    let lead = line_indent(text, pos);
    let line_start = text[..pos].rfind('\n').map_or(0, |k| k + 1);
    if line_start + lead.len() == pos {
        lead.to_string()
    } else {
        format!("{lead}  ")
    }
}

fn indent_lines(snippet: &str, indent: &str) -> String {
    snippet.replace('\n', &format!("\n{indent}"))
}

impl Model {
    /// The URDF `urdf` (the text the model was imported from, named `file` in errors) with
    /// the `<inertial>` of every link carrying identified inertia replaced by `params`,
    /// everything else byte for byte as it was. Links without identified inertia (the
    /// root) keep theirs; a link without `<inertial>` gets one.
    ///
    /// The URDF's links must be the model's frames (same names, parents and poses), since
    /// the parameters are expressed in those frames.
    ///
    /// ```
    /// use dvrk_model::{inertia, Model};
    /// let urdf = r#"<robot name="pendulum">
    ///   <link name="world"/>
    ///   <link name="arm"><visual><geometry><box size="0.1 0.1 1"/></geometry></visual></link>
    ///   <joint name="swing" type="continuous">
    ///     <parent link="world"/><child link="arm"/><axis xyz="0 1 0"/>
    ///   </joint>
    /// </robot>"#;
    /// let model = Model::from_urdf_str(urdf, "pendulum.urdf").unwrap();
    /// let mut params = vec![0.0; model.n_params()];
    /// let bary = inertia::barycentric_from_standard(2.0, [0.0, 0.0, -0.5], [0.1, 0.0, 0.0, 0.1, 0.0, 0.01]);
    /// params[..10].copy_from_slice(&bary);
    /// let out = model.urdf_with_inertials(&params, urdf, "pendulum.urdf").unwrap();
    /// assert!(out.contains(r#"<mass value="2"/>"#));
    /// assert!(out.contains(r#"<box size="0.1 0.1 1"/>"#)); // the rest is untouched
    /// let back = Model::from_urdf_str(&out, "out.urdf").unwrap();
    /// assert_eq!(back.nominal_parameters().unwrap(), params);
    /// ```
    pub fn urdf_with_inertials(
        &self,
        params: &[f64],
        urdf: &str,
        file: &str,
    ) -> Result<String, ModelError> {
        self.check_export_params(params)?;
        let inertials = self.export_inertials(params)?;
        let theirs = Model::from_urdf_str(urdf, file)?;
        self.check_same_links(&theirs, file)?;
        let mut snippets = HashMap::new();
        for (f, s) in self.frames.iter().zip(&inertials[1..]) {
            if let Some(s) = s {
                let mut text = String::new();
                let mut ser = quick_xml::se::Serializer::with_root(&mut text, Some("inertial"))
                    .map_err(|e| self.urdf_error(file, e))?;
                ser.indent(' ', 2);
                urdf_inertial(Some(s))
                    .serialize(ser)
                    .map_err(|e| self.urdf_error(file, e))?;
                snippets.insert(f.name.as_str(), text);
            }
        }
        splice_inertials(urdf, file, &snippets)
    }

    fn urdf_error(&self, file: &str, e: impl std::fmt::Display) -> ModelError {
        ModelError::Urdf {
            file: file.to_string(),
            message: e.to_string(),
        }
    }

    /// Whether `theirs` (imported from `file`) has exactly our frames: names, parents,
    /// joint kinds, coordinates, and poses at a few configurations.
    fn check_same_links(&self, theirs: &Model, file: &str) -> Result<(), ModelError> {
        let err = |message: String| ModelError::Urdf {
            file: file.to_string(),
            message: format!(
                "its links do not match robot `{}` ({}): {message}",
                self.name, self.source
            ),
        };
        let ours: Vec<&str> = self.frames.iter().map(|f| f.name.as_str()).collect();
        let their: Vec<&str> = theirs.frames.iter().map(|f| f.name.as_str()).collect();
        let missing: Vec<&str> = ours
            .iter()
            .copied()
            .filter(|n| !their.contains(n))
            .collect();
        let extra: Vec<&str> = their
            .iter()
            .copied()
            .filter(|n| !ours.contains(n))
            .collect();
        if !missing.is_empty() || !extra.is_empty() {
            let mut m = String::new();
            if !missing.is_empty() {
                m += &format!("no link named {}", missing.join(", "));
            }
            if !extra.is_empty() {
                if !m.is_empty() {
                    m += "; ";
                }
                m += &format!("links not in the robot: {}", extra.join(", "));
            }
            return Err(err(m));
        }
        let our_names = self.frame_names();
        let their_names = theirs.frame_names();
        let index: HashMap<&str, usize> =
            their.iter().enumerate().map(|(i, n)| (*n, i + 1)).collect();
        for (i, f) in self.frames.iter().enumerate() {
            let g = theirs.frame(index[f.name.as_str()]);
            let (pa, pb) = (&our_names[f.parent], &their_names[g.parent]);
            if pa != pb {
                return Err(err(format!(
                    "link `{}` hangs from `{pb}`, frame {} from `{pa}`",
                    f.name,
                    i + 1
                )));
            }
            if f.kind != g.kind {
                return Err(err(format!(
                    "joint of link `{}` is {:?}, the robot's is {:?}",
                    f.name, g.kind, f.kind
                )));
            }
        }
        let mut coords_ours = self.coordinates.clone();
        let mut coords_theirs = theirs.coordinates.clone();
        coords_ours.sort();
        coords_theirs.sort();
        if coords_ours != coords_theirs {
            return Err(err(format!(
                "joints {:?}, robot coordinates {:?}",
                theirs.coordinates, self.coordinates
            )));
        }
        let to_theirs: Vec<usize> = theirs
            .coordinates
            .iter()
            .map(|c| self.coordinates.iter().position(|d| d == c).unwrap())
            .collect();
        for trial in 0..3 {
            let q: Vec<f64> = (0..self.dof())
                .map(|k| 0.37 * trial as f64 * (1.3 * k as f64 + 0.7).sin())
                .collect();
            let q_theirs: Vec<f64> = to_theirs.iter().map(|&k| q[k]).collect();
            let a = self.frame_poses(&q);
            let b = theirs.frame_poses(&q_theirs);
            for (i, f) in self.frames.iter().enumerate() {
                let (x, y) = (&a[i + 1], &b[index[f.name.as_str()]]);
                let d = (x.rotation - y.rotation)
                    .abs()
                    .max()
                    .max((x.translation - y.translation).abs().max());
                if d > 1e-9 {
                    return Err(err(format!(
                        "link `{}` is not where frame {} is (pose differs by {d:e} at q = {q:?})",
                        f.name,
                        i + 1
                    )));
                }
            }
        }
        Ok(())
    }
}

/// Replaces (or inserts) the `<inertial>` of the links named in `snippets`, keeping every
/// other byte of `text`.
fn splice_inertials(
    text: &str,
    file: &str,
    snippets: &HashMap<&str, String>,
) -> Result<String, ModelError> {
    use quick_xml::events::{BytesStart, Event};
    let err = |message: String| ModelError::Urdf {
        file: file.to_string(),
        message,
    };
    let mut reader = quick_xml::Reader::from_str(text);
    let decoder = reader.decoder();
    let name_of = |e: &BytesStart<'_>| -> Result<String, ModelError> {
        let attr = e
            .try_get_attribute("name")
            .map_err(|e| err(e.to_string()))?
            .ok_or_else(|| err("a <link> has no name".into()))?;
        Ok(attr
            .decode_and_unescape_value(decoder)
            .map_err(|e| err(e.to_string()))?
            .into_owned())
    };
    let mut splice = Splice {
        text,
        snippets,
        edits: Vec::new(),
        depth: 0,
        link: None,
        inertial_start: None,
        done: HashSet::new(),
    };
    loop {
        let start = reader.buffer_position() as usize;
        let event = reader
            .read_event()
            .map_err(|e| err(format!("cannot parse the document: {e}")))?;
        let end = reader.buffer_position() as usize;
        match event {
            Event::Start(e) => {
                let tag = e.local_name();
                let link = splice
                    .is_link(tag.as_ref())
                    .then(|| name_of(&e))
                    .transpose()?;
                splice.open(tag.as_ref(), link, start, end);
            }
            Event::End(e) => splice.close(e.local_name().as_ref(), start, end),
            Event::Empty(e) => {
                let tag = e.local_name();
                let link = splice
                    .is_link(tag.as_ref())
                    .then(|| name_of(&e))
                    .transpose()?;
                splice.empty(tag.as_ref(), link, start, end);
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if let Some(missing) = snippets.keys().find(|k| !splice.done.contains(**k)) {
        return Err(err(format!("link `{missing}` not found in the document")));
    }
    Ok(splice.apply())
}

/// The edits of [`splice_inertials`], gathered while the document is read.
struct Splice<'a> {
    text: &'a str,
    snippets: &'a HashMap<&'a str, String>,
    /// (start, end, replacement) byte spans.
    edits: Vec<(usize, usize, String)>,
    depth: usize,
    /// The open link: its name, where its start tag ends, whether it had an inertial.
    link: Option<(String, usize, bool)>,
    inertial_start: Option<usize>,
    /// The links whose inertial was replaced or inserted.
    done: HashSet<String>,
}

impl Splice<'_> {
    /// Whether `tag` at the current depth is a link of the robot.
    fn is_link(&self, tag: &[u8]) -> bool {
        self.depth == 1 && tag == b"link"
    }

    /// A start tag spanning `start..end`; `link` is the name of a link's.
    fn open(&mut self, tag: &[u8], link: Option<String>, start: usize, end: usize) {
        if let Some(name) = link {
            self.link = Some((name, end, false));
        } else if self.depth == 2 && tag == b"inertial" && self.link.is_some() {
            self.inertial_start = Some(start);
        }
        self.depth += 1;
    }

    /// An end tag spanning `start..end`: an inertial replaced, or one inserted at the end
    /// of a link that had none.
    fn close(&mut self, tag: &[u8], start: usize, end: usize) {
        self.depth -= 1;
        let text = self.text;
        if self.depth == 2 && tag == b"inertial" {
            if let (Some(s), Some((name, _, had))) = (self.inertial_start.take(), &mut self.link) {
                *had = true;
                if let Some(snippet) = self.snippets.get(name.as_str()) {
                    let replacement = indent_lines(snippet, &element_indent(text, s));
                    self.edits.push((s, end, replacement));
                    self.done.insert(name.clone());
                }
            }
        } else if self.depth == 1 && tag == b"link" {
            if let Some((name, tag_end, had)) = self.link.take() {
                if let (false, Some(snippet)) = (had, self.snippets.get(name.as_str())) {
                    let inner = format!("{}  ", line_indent(text, start));
                    self.edits.push((
                        tag_end,
                        tag_end,
                        format!("\n{inner}{}", indent_lines(snippet, &inner)),
                    ));
                    self.done.insert(name);
                }
            }
        }
    }

    /// An empty element spanning `start..end` (`link`: the name of a link's): a link
    /// opened to take an inertial, or an empty inertial replaced.
    fn empty(&mut self, tag: &[u8], link: Option<String>, start: usize, end: usize) {
        let text = self.text;
        if let Some(name) = link {
            if let Some(snippet) = self.snippets.get(name.as_str()) {
                let indent = line_indent(text, start);
                let inner = format!("{indent}  ");
                let open = text[start..end].trim_end_matches('>').trim_end_matches('/');
                self.edits.push((
                    start,
                    end,
                    format!(
                        "{}>\n{inner}{}\n{indent}</link>",
                        open.trim_end(),
                        indent_lines(snippet, &inner)
                    ),
                ));
                self.done.insert(name);
            }
        } else if self.depth == 2 && tag == b"inertial" {
            if let Some((name, _, had)) = &mut self.link {
                *had = true;
                if let Some(snippet) = self.snippets.get(name.as_str()) {
                    let replacement = indent_lines(snippet, &element_indent(text, start));
                    self.edits.push((start, end, replacement));
                    self.done.insert(name.clone());
                }
            }
        }
    }

    /// The text with the edits applied.
    fn apply(mut self) -> String {
        self.edits.sort_by_key(|e| e.0);
        let text = self.text;
        let mut out = String::with_capacity(text.len() + 256 * self.edits.len());
        let mut at = 0;
        for (s, e, replacement) in self.edits {
            out.push_str(&text[at..s]);
            out.push_str(&replacement);
            at = e;
        }
        out.push_str(&text[at..]);
        out
    }
}
