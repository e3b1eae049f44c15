//! A URDF's text: what calbench reads of it, and the same text written back with joint
//! origins replaced (docs/formats.md, "URDF robots").
//!
//! calbench reads the `<robot>` element's name, its links' names and, of its joints, the
//! `<origin>`, `<parent>`, `<child>`, `<axis>` and `<limit>`. Every other element (a link's
//! visuals, collisions and inertial, the robot's materials, transmissions and Gazebo tags, a
//! joint's dynamics or mimic) is set aside before urdf-rs parses the file, so that a part
//! calbench does not read cannot refuse the robot: urdf-rs refuses, for example, a `<visual>`
//! holding two `<material>` elements, as ROS-Industrial's IRB 4600 URDFs write them. The text
//! is kept as it was read, and a written URDF is that text with only the changed `<origin>`
//! elements replaced, so that nothing set aside is lost.

use std::ops::Range;
use std::path::Path;

use quick_xml::events::Event;

use crate::error::{line_of, Error, Result};
use crate::numeric::{matrix_rpy, Frame, Real};

/// The children of a `<joint>` that calbench reads.
const JOINT_READS: [&[u8]; 5] = [b"origin", b"parent", b"child", b"axis", b"limit"];

/// A URDF's text and where each of its joints' `<origin>` is written.
#[derive(Clone, Debug)]
pub(super) struct Source {
    /// The file's text as read.
    text: String,
    /// Per `<joint>` child of the robot, in the order written: the span of its `<origin>`,
    /// or, when it has none, an empty span just after its start tag.
    origins: Vec<Range<usize>>,
    /// The offset of the robot's end tag.
    end: usize,
}

/// Reads the URDF at `path`: what calbench reads of it as urdf-rs parses it, and its text. A
/// text that is not well-formed XML is refused naming the file and the line.
pub(super) fn read(path: &Path) -> Result<(urdf_rs::Robot, Source)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    // quick-xml skips a byte order mark without counting it in its offsets: the reader reads
    // the text after the marks (one or more), and the offsets into `text` are its offsets
    // plus their length.
    let body = text.trim_start_matches('\u{feff}');
    let base = text.len() - body.len();
    let bad = |at: usize, e: String| Error::file(path, format!("line {}", line_of(&text, at)), e);
    let mut reader = quick_xml::Reader::from_str(body);
    // The names of the open elements, the robot first.
    let mut open: Vec<Vec<u8>> = Vec::new();
    // The element set aside that is open: its start and its depth.
    let mut aside: Option<(usize, usize)> = None;
    let mut cuts: Vec<Range<usize>> = Vec::new();
    let mut origins = Vec::new();
    // Where the joint's `<origin>` being read began (one written as a start and an end tag).
    let mut origin_at = None;
    let mut end = None;
    // The offsets of the robot's `<link>` and `<joint>` children, in the order written.
    let (mut links_at, mut joints_at) = (Vec::new(), Vec::new());
    loop {
        let at = base + reader.buffer_position() as usize;
        let event = reader
            .read_event()
            .map_err(|e| bad(base + reader.error_position() as usize, e.to_string()))?;
        let after = base + reader.buffer_position() as usize;
        let (e, empty) = match &event {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) => {
                open.pop();
                if let Some((start, depth)) = aside {
                    if depth == open.len() {
                        cuts.push(start..after);
                        aside = None;
                    }
                }
                if open.len() == 2 && aside.is_none() {
                    if let (Some(s), Some(o)) = (origin_at.take(), origins.last_mut()) {
                        *o = s..after;
                    }
                }
                if open.is_empty() {
                    end = Some(at);
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let name = e.name().as_ref().to_vec();
        // XML has one root element; quick-xml reads on after its end.
        if let (true, Some(root_end)) = (open.is_empty(), end) {
            let msg = format!(
                "<{}> after the end of the root element on line {}: a URDF is one <robot> \
                 element",
                String::from_utf8_lossy(&name),
                line_of(&text, root_end),
            );
            return Err(bad(at, msg));
        }
        if aside.is_none() {
            let parent = open.get(1).map(Vec::as_slice);
            // A link or joint inside another one (a misplaced end tag) would be set aside, and
            // the robot read without it.
            if open.len() == 2 && (name == b"link" || name == b"joint") {
                let (outer, at_outer) = match parent {
                    Some(b"joint") => ("joint", joints_at.last()),
                    _ => ("link", links_at.last()),
                };
                let msg = format!(
                    "<{}> inside the <{outer}> of line {}: links and joints are children of \
                     <robot>",
                    String::from_utf8_lossy(&name),
                    line_of(&text, at_outer.copied().unwrap_or(0)),
                );
                return Err(bad(at, msg));
            }
            let kept = match open.len() {
                0 => true,
                1 => name == b"link" || name == b"joint",
                2 => parent == Some(b"joint") && JOINT_READS.contains(&name.as_slice()),
                _ => true,
            };
            if !kept && empty {
                cuts.push(at..after);
            } else if !kept {
                aside = Some((at, open.len()));
            } else if open.len() == 1 && name == b"link" {
                links_at.push(at);
            } else if open.len() == 1 && name == b"joint" {
                joints_at.push(at);
                origins.push(after..after);
            } else if open.len() == 2 && name == b"origin" {
                let first = origins.last().is_some_and(Range::is_empty);
                match (first, empty) {
                    (true, true) => *origins.last_mut().expect("a joint is open") = at..after,
                    (true, false) => origin_at = Some(at),
                    _ => {}
                }
            }
        }
        if !empty {
            open.push(name);
        }
    }
    // A text without a root element is refused by urdf-rs.
    let end = end.unwrap_or(text.len());
    let mut read = String::with_capacity(text.len());
    let mut from = 0;
    for c in &cuts {
        read.push_str(&text[from..c.start]);
        from = c.end;
    }
    read.push_str(&text[from..]);
    let robot =
        urdf_rs::read_from_string(&read).map_err(|e| Error::file(path, "URDF", e.to_string()))?;
    if robot.joints.len() != origins.len() {
        return Err(Error::Compute(format!(
            "{}: urdf-rs read {} joints where the text has {}",
            path.display(),
            robot.joints.len(),
            origins.len()
        )));
    }
    let links = with_lines(&text, &robot.links, |l| &l.name, &links_at);
    let joints = with_lines(&text, &robot.joints, |j| &j.name, &joints_at);
    if let Some((at, msg)) = tree_fault(&robot, &links, &joints) {
        return Err(Error::file(path, format!("line {at}"), msg));
    }
    let source = Source { text, origins, end };
    Ok((robot, source))
}

/// Each item's name with the line of `text` it starts on, from its byte offset in `at`.
fn with_lines<'a, T>(
    text: &str,
    items: &'a [T],
    name: impl Fn(&'a T) -> &'a String,
    at: &[usize],
) -> Vec<(&'a str, usize)> {
    let lines = at.iter().map(|&a| line_of(text, a));
    items.iter().map(|i| name(i).as_str()).zip(lines).collect()
}

/// The first fault, with its line, of the links and joints of `robot` (each with the line
/// it starts on) as a tree: a link or joint name given twice, a joint whose parent or child
/// is not a link of the robot, a link that is the child of two joints, a second root link or
/// a loop. urdfdom refuses
/// each of them; calbench would read one of the two and write back the other unchanged.
fn tree_fault(
    robot: &urdf_rs::Robot,
    links: &[(&str, usize)],
    joints: &[(&str, usize)],
) -> Option<(usize, String)> {
    for (what, named) in [("link", links), ("joint", joints)] {
        for (k, (name, at)) in named.iter().enumerate() {
            if let Some((_, first)) = named[..k].iter().find(|(n, _)| n == name) {
                return Some((
                    *at,
                    format!("{what} \"{name}\": already declared on line {first}"),
                ));
            }
        }
    }
    for (k, (j, &(name, at))) in robot.joints.iter().zip(joints).enumerate() {
        for (key, link) in [
            ("<parent link>", &j.parent.link),
            ("<child link>", &j.child.link),
        ] {
            if !links.iter().any(|(l, _)| l == link) {
                return Some((
                    at,
                    format!("joint \"{name}\", {key}: no link \"{link}\" in the URDF"),
                ));
            }
        }
        let child = &j.child.link;
        if let Some(i) = robot.joints[..k]
            .iter()
            .position(|p| &p.child.link == child)
        {
            let (other, first) = joints[i];
            return Some((at, format!("joint \"{name}\", <child link>: link \"{child}\" is already the child of joint \"{other}\" (line {first})")));
        }
    }
    // Every link hangs from the one root link: no second root, no loop.
    let parent = |l: &str| {
        let k = robot.joints.iter().position(|j| j.child.link == l)?;
        Some((robot.joints[k].parent.link.as_str(), joints[k]))
    };
    let mut roots = links.iter().filter(|(l, _)| parent(l).is_none());
    if let (Some((first, _)), Some((second, at))) = (roots.next(), roots.next()) {
        let msg = format!(
            "link \"{second}\": a second root link (no joint has it as its child) besides \
             \"{first}\""
        );
        return Some((*at, msg));
    }
    for &(l, _) in links {
        let mut link = l;
        for _ in 0..=joints.len() {
            match parent(link) {
                Some((up, _)) => link = up,
                None => break,
            }
        }
        if let Some((_, (name, at))) = parent(link) {
            let msg = format!("joint \"{name}\": the joints form a loop at link \"{link}\"");
            return Some((at, msg));
        }
    }
    None
}

/// A number as a written URDF holds it: every digit, and 0 for −0.
pub(super) fn number(x: Real) -> String {
    let x = if x == 0.0 { 0.0 } else { x };
    format!("{x:?}")
}

/// The `<origin>` element of the frame `o` (mm): `xyz` in m, `rpy` in rad.
pub(super) fn origin_element(o: &Frame) -> String {
    let r = matrix_rpy(&o.rot);
    format!(
        "<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
        number(o.pos.x / 1000.0),
        number(o.pos.y / 1000.0),
        number(o.pos.z / 1000.0),
        number(r[0]),
        number(r[1]),
        number(r[2])
    )
}

/// The indentation of the line holding the offset `at` of `text`.
fn indent_at(text: &str, at: usize) -> &str {
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line = &text[start..];
    &line[..line.len() - line.trim_start().len()]
}

impl Source {
    /// The text with the `<origin>` of the `i`-th joint set to each `(i, frame)` of
    /// `origins` (added after the joint's start tag where it has none) and `added`, whole
    /// lines of elements, written before the robot's end tag.
    pub(super) fn with(&self, origins: &[(usize, Frame)], added: &str) -> String {
        let t = &self.text;
        let mut edits: Vec<(Range<usize>, String)> = origins
            .iter()
            .map(|(i, f)| {
                let span = self.origins[*i].clone();
                let element = origin_element(f);
                if span.is_empty() {
                    let inner = format!("{}  ", indent_at(t, span.start));
                    (span, format!("\n{inner}{element}"))
                } else {
                    (span, element)
                }
            })
            .collect();
        if !added.is_empty() {
            // On a line of its own when the end tag is alone on its line.
            let line_start = t[..self.end].rfind('\n').map_or(0, |i| i + 1);
            if t[line_start..self.end].trim().is_empty() {
                edits.push((line_start..line_start, added.to_string()));
            } else {
                edits.push((self.end..self.end, format!("\n{added}")));
            }
        }
        edits.sort_by_key(|(span, _)| span.start);
        let mut out = String::with_capacity(t.len() + 256);
        let mut from = 0;
        for (span, s) in edits {
            out.push_str(&t[from..span.start]);
            out.push_str(&s);
            from = span.end;
        }
        out.push_str(&t[from..]);
        out
    }
}
