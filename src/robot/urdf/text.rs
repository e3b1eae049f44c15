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

use quick_xml::events::{BytesStart, Event};

use super::{not_one_axis, OFF_CHAIN, ONE_AXIS};
use crate::error::{line_of, read_text_whole, Error, Opt, Result, Said};
use crate::numeric::{matrix_rpy, Frame, Real};

/// The children of a `<joint>` that calbench reads.
const JOINT_READS: [&[u8]; 5] = [b"origin", b"parent", b"child", b"axis", b"limit"];

/// A URDF's text and where each of its joints and their elements are written.
#[derive(Clone, Debug)]
pub(super) struct Source {
    /// The file's text as read.
    text: String,
    /// The `<joint>` children of the robot, in the order written (urdf-rs's order).
    joints: Vec<Part>,
    /// The offset of the robot's end tag.
    end: usize,
}

/// A `<link>` or `<joint>` of the robot, where it is written: what a refusal of urdf-rs is
/// traced to, and a joint's elements are written over.
#[derive(Clone, Debug)]
struct Part {
    /// `link` or `joint`.
    kind: &'static str,
    /// Its `name` attribute.
    name: String,
    /// The element, and its start tag.
    span: Range<usize>,
    tag: Range<usize>,
    /// A joint's children that calbench reads, each with its name.
    children: Vec<(Range<usize>, String)>,
    /// A joint's `<mimic>`, set aside unread: where it starts, and the joint it names.
    mimic: Option<(usize, String)>,
}

/// Reads the URDF at `path`: what calbench reads of it as urdf-rs parses it, and its text. A
/// text that is not well-formed XML is refused naming the file and the line.
pub(super) fn read(path: &Path) -> Result<(urdf_rs::Robot, Source)> {
    let text = read_text_whole(path)?;
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
    let mut end = None;
    // The robot's start tag, and its links and joints as written.
    let mut robot_tag = 0..0;
    let mut parts: Vec<Part> = Vec::new();
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
                match aside {
                    Some((start, depth)) if depth == open.len() => {
                        cuts.push(start..after);
                        aside = None;
                    }
                    Some(_) => {}
                    None => match (open.len(), parts.last_mut()) {
                        (1, Some(part)) => part.span.end = after,
                        (2, Some(part)) => {
                            if let Some((span, _)) = part.children.last_mut() {
                                span.end = after;
                            }
                        }
                        _ => {}
                    },
                }
                if open.is_empty() {
                    end = Some(at);
                }
                continue;
            }
            Event::Eof => break,
            // The URDF parser refuses a comment holding `--`, which quick-xml and urdfdom
            // read; calbench reads no comment (one in an element set aside goes with it).
            Event::Comment(_) if aside.is_none() => {
                cuts.push(at..after);
                continue;
            }
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
        if open.is_empty() && name != b"robot" {
            let msg = format!(
                "the root element is <{}>: a URDF is one <robot> element",
                String::from_utf8_lossy(&name)
            );
            return Err(bad(at, msg));
        }
        if aside.is_none() {
            let parent = open.get(1).map(Vec::as_slice);
            // A link or joint inside another one (a misplaced end tag) would be set aside, and
            // the robot read without it.
            if open.len() == 2 && (name == b"link" || name == b"joint") {
                let outer = parts.last().expect("a link or joint is open");
                let msg = format!(
                    "<{}> inside the <{}> of line {}: links and joints are children of <robot>",
                    String::from_utf8_lossy(&name),
                    outer.kind,
                    line_of(&text, outer.tag.start),
                );
                return Err(bad(at, msg));
            }
            let kept = match open.len() {
                0 => true,
                1 => name == b"link" || name == b"joint",
                2 => parent == Some(b"joint") && JOINT_READS.contains(&name.as_slice()),
                _ => true,
            };
            if kept {
                let part = parts.last().filter(|_| open.len() == 2);
                check_attributes(e, part).map_err(|msg| bad(at, msg))?;
                match open.len() {
                    0 => {
                        if attribute(e, b"name").is_none_or(|n| n.trim().is_empty()) {
                            let msg = "<robot>: its `name` is missing or empty: it names the \
                                       robot in reports, and `identify` names the compensated \
                                       robot `<name>-calibrated`";
                            return Err(bad(at, msg.into()));
                        }
                        robot_tag = at..after;
                        // `<robot/>` ends where it starts.
                        end = end.or(Some(at).filter(|_| empty));
                    }
                    1 => parts.push(Part {
                        kind: if name == b"link" { "link" } else { "joint" },
                        name: attribute(e, b"name").unwrap_or_default(),
                        span: at..after,
                        tag: at..after,
                        children: Vec::new(),
                        mimic: None,
                    }),
                    2 => {
                        let child = String::from_utf8_lossy(&name).into_owned();
                        let part = parts.last_mut().expect("a joint is open");
                        part.children.push((at..after, child));
                    }
                    _ => {}
                }
            }
            if open.len() == 2 && parent == Some(b"joint") && name == b"mimic" {
                let part = parts.last_mut().expect("a joint is open");
                part.mimic = Some((at, attribute(e, b"joint").unwrap_or_default()));
            }
            if !kept && empty {
                cuts.push(at..after);
            } else if !kept {
                aside = Some((at, open.len()));
            }
        }
        if !empty {
            open.push(name);
        }
    }
    let Some(end) = end.filter(|_| !robot_tag.is_empty()) else {
        if let Some(inner) = open.last().filter(|_| !robot_tag.is_empty()) {
            let msg = format!(
                "the file ends inside <{}>: the <robot> of line {} is not closed (a file cut \
                 short?)",
                String::from_utf8_lossy(inner),
                line_of(&text, robot_tag.start)
            );
            // The file's last line: a final newline ends it and starts none.
            return Err(bad(text.len() - usize::from(text.ends_with('\n')), msg));
        }
        let msg = "no <robot> element: a URDF is one <robot> element";
        return Err(Error::file(path, "URDF", msg));
    };
    let read = without(&text, &cuts, 0..text.len());
    let robot = urdf_rs::read_from_string(&read).map_err(|e| {
        match refused_part(&text, &cuts, robot_tag, &parts) {
            Some((at, msg)) => bad(at, msg),
            None => Error::file(path, "URDF", e.to_string()),
        }
    })?;
    let (joint_parts, link_parts): (Vec<Part>, Vec<Part>) =
        parts.into_iter().partition(|p| p.kind == "joint");
    if robot.joints.len() != joint_parts.len() {
        return Err(Error::Compute(format!(
            "{}: urdf-rs read {} joints where the text has {}",
            path.display(),
            robot.joints.len(),
            joint_parts.len()
        )));
    }
    let links = with_lines(&text, robot.links.iter().map(|l| &l.name), &link_parts);
    let joints = with_lines(&text, robot.joints.iter().map(|j| &j.name), &joint_parts);
    if let Some((at, msg)) = tree_fault(&robot, &links, &joints) {
        return Err(Error::file(path, format!("line {at}"), msg));
    }
    let source = Source {
        text,
        joints: joint_parts,
        end,
    };
    Ok((robot, source))
}

/// Each of `names`, the names urdf-rs read of the elements `parts` (all links or all joints),
/// with the line of `text` its element starts on.
fn with_lines<'a>(
    text: &str,
    names: impl Iterator<Item = &'a String>,
    parts: &[Part],
) -> Vec<(&'a str, usize)> {
    // The parts stand in the text's order: each line is counted on from the last part's.
    let (mut at, mut line) = (0, 1);
    let lines = parts.iter().map(|p| {
        let start = p.tag.start.min(text.len());
        if start < at {
            (at, line) = (0, 1);
        }
        line += text.as_bytes()[at..start]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        at = start;
        line
    });
    names.map(String::as_str).zip(lines).collect()
}

/// The text of `span` of `text` without the `cuts` (sorted, not overlapping) that lie in it.
fn without(text: &str, cuts: &[Range<usize>], span: Range<usize>) -> String {
    let mut kept = String::with_capacity(span.len());
    let mut from = span.start;
    for c in cuts.iter().filter(|c| span.contains(&c.start)) {
        kept.push_str(&text[from..c.start]);
        from = c.end;
    }
    kept.push_str(&text[from..span.end]);
    kept
}

/// The value of the attribute `key` of `e`, unescaped.
fn attribute(e: &BytesStart, key: &[u8]) -> Option<String> {
    let a = e.try_get_attribute(key).ok()??;
    a.unescape_value().ok().map(|v| v.into_owned())
}

/// Refuses an element calbench reads whose attributes urdf-rs would misread or refuse
/// without naming where: an attribute written twice, an entity that is not XML's, a
/// joint's `<origin>` or `<axis>` whose `xyz` or `rpy` is not three numbers (urdf-rs reads
/// the numbers among the words, so that `"0 zero 1 2"` would be the vector (0, 1, 2)) and a
/// `<limit>` value that is not a number; and a joint of a type URDF does not define (urdf-rs
/// would offer `floating`, `planar` and `spherical` for a type it does not know). URDF's
/// `floating` and `planar` pass: off the chain they are not read, and on it they are refused.
/// `joint` is the joint an element at depth 2 belongs to.
fn check_attributes(e: &BytesStart, joint: Option<&Part>) -> std::result::Result<(), String> {
    let element = String::from_utf8_lossy(e.name().as_ref()).into_owned();
    for a in e.attributes() {
        let a = a.map_err(|err| format!("<{element}>: {err}"))?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let value = a
            .unescape_value()
            .map_err(|err| format!("<{element} {key}>: {err}"))?;
        // A name is shown in reports and on the terminal (and a character XML does not take,
        // as `&#7;`, was refused by urdf-rs at a position in a piece of the file).
        if key == "name" && joint.is_none() && value.chars().any(crate::error::is_hidden) {
            return Err(format!(
                "<{element} name>: {value:?} holds a control character (bidirectional \
                 overrides included): a name is shown in reports and on the terminal"
            ));
        }
        let known = |t: &str| ONE_AXIS.contains(&t) || OFF_CHAIN.contains(&t);
        if element == "joint" && joint.is_none() && key == "type" && !known(&value) {
            let name = attribute(e, b"name").unwrap_or_default();
            return Err(not_one_axis(&name, &value));
        }
        let Some(joint) = joint else { continue };
        let numbers = match (element.as_str(), key.as_str()) {
            ("origin" | "axis", "xyz") | ("origin", "rpy") => 3,
            ("limit", "lower" | "upper" | "effort" | "velocity") => 1,
            _ => continue,
        };
        let words: Vec<&str> = value.split_whitespace().collect();
        if words.len() != numbers || words.iter().any(|w| w.parse::<f64>().is_err()) {
            let what = if numbers == 1 {
                "a number"
            } else {
                "three numbers"
            };
            return Err(format!(
                "joint \"{}\", <{element} {key}>: \"{value}\" is not {what}",
                joint.name
            ));
        }
        let tiny = words
            .iter()
            .find_map(|w| crate::error::underflow(w, w.parse().ok()?));
        if let Some(msg) = tiny {
            return Err(format!(
                "joint \"{}\", <{element} {key}>: {msg}",
                joint.name
            ));
        }
    }
    Ok(())
}

/// Where urdf-rs's refusal of the text lies, which it does not say: the first link or joint
/// it refuses read alone in the robot's element, and of a joint the first child it refuses
/// read alone in the joint (beside a stand-in parent and child). The offset of that element
/// and the refusal, or `None` when urdf-rs refuses the robot's start tag itself.
fn refused_part(
    text: &str,
    cuts: &[Range<usize>],
    robot_tag: Range<usize>,
    parts: &[Part],
) -> Option<(usize, String)> {
    let refusal = |body: &str| {
        let doc = format!("{}{body}</robot>", &text[robot_tag.clone()]);
        let e = urdf_rs::read_from_string(&doc).err()?;
        Some(e.to_string().trim_start_matches("custom: ").to_string())
    };
    if robot_tag.is_empty() || refusal("").is_some() {
        return None;
    }
    let part = parts
        .iter()
        .find_map(|p| Some((p, refusal(&without(text, cuts, p.span.clone()))?)))?;
    let (p, msg) = part;
    let whole = match p.name.as_str() {
        "" => format!("<{}>: {msg}", p.kind),
        name => format!("{} \"{name}\": {msg}", p.kind),
    };
    if p.kind != "joint" || p.tag == p.span {
        return Some((p.tag.start, whole));
    }
    let alone = |child: Option<(&str, String)>| {
        let mut body = text[p.tag.clone()].to_string();
        for stand_in in ["parent", "child"] {
            if child.as_ref().is_none_or(|(name, _)| *name != stand_in) {
                body.push_str(&format!("<{stand_in} link=\"{stand_in}\"/>"));
            }
        }
        body.push_str(&child.map(|(_, text)| text).unwrap_or_default());
        refusal(&format!("{body}</joint>"))
    };
    if alone(None).is_some() {
        return Some((p.tag.start, whole));
    }
    p.children
        .iter()
        .find_map(|(span, name)| {
            let msg = alone(Some((name, without(text, cuts, span.clone()))))?;
            Some((span.start, format!("joint \"{}\", <{name}>: {msg}", p.name)))
        })
        .or(Some((p.tag.start, whole)))
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
    use std::collections::{HashMap, HashSet};
    for (what, named) in [("link", links), ("joint", joints)] {
        let mut first_at = HashMap::with_capacity(named.len());
        for &(name, at) in named {
            if let Some(first) = first_at.insert(name, at) {
                return Some((
                    at,
                    format!("{what} \"{name}\": already declared on line {first}"),
                ));
            }
        }
    }
    let known: HashSet<&str> = links.iter().map(|(l, _)| *l).collect();
    let child_of = child_joints(robot);
    for (k, (j, &(name, at))) in robot.joints.iter().zip(joints).enumerate() {
        for (key, link) in [
            ("<parent link>", &j.parent.link),
            ("<child link>", &j.child.link),
        ] {
            if !known.contains(link.as_str()) {
                return Some((
                    at,
                    format!("joint \"{name}\", {key}: no link \"{link}\" in the URDF"),
                ));
            }
        }
        let child = &j.child.link;
        if let Some(&i) = child_of.get(child.as_str()).filter(|&&i| i < k) {
            let (other, first) = joints[i];
            return Some((at, format!("joint \"{name}\", <child link>: link \"{child}\" is already the child of joint \"{other}\" (line {first})")));
        }
    }
    // Every link hangs from the one root link: no second root, no loop.
    let parent = |l: &str| {
        let &k = child_of.get(l)?;
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
    // A link whose walk up reaches the root is known to hang from it, and so is every link on
    // the way: each is walked once while none loops.
    let mut hangs = HashSet::with_capacity(links.len());
    for &(l, _) in links {
        let mut link = l;
        let mut path = Vec::new();
        for _ in 0..=joints.len() {
            if hangs.contains(link) {
                break;
            }
            path.push(link);
            match parent(link) {
                Some((up, _)) => link = up,
                None => break,
            }
        }
        match parent(link) {
            Some((_, (name, at))) if !hangs.contains(link) => {
                let msg = format!("joint \"{name}\": the joints form a loop at link \"{link}\"");
                return Some((at, msg));
            }
            _ => hangs.extend(path),
        }
    }
    None
}

/// The joint of each child link, by its index in `urdf.joints`: the first, where a link is
/// the child of several (which [`read`] refuses).
pub(super) fn child_joints(urdf: &urdf_rs::Robot) -> std::collections::HashMap<&str, usize> {
    let mut map = std::collections::HashMap::with_capacity(urdf.joints.len());
    for (i, j) in urdf.joints.iter().enumerate() {
        map.entry(j.child.link.as_str()).or_insert(i);
    }
    map
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
    /// The span of the `i`-th joint's first `element` (`origin`, `axis`, `limit`), if it has
    /// one.
    fn element(&self, i: usize, element: &str) -> Option<&Range<usize>> {
        let children = &self.joints[i].children;
        children
            .iter()
            .find(|(_, name)| name == element)
            .map(|(span, _)| span)
    }

    /// The span of the `<origin>` of the `i`-th joint, or, when it has none, an empty span
    /// just after its start tag.
    fn origin(&self, i: usize) -> Range<usize> {
        let after = self.joints[i].tag.end;
        self.element(i, "origin").cloned().unwrap_or(after..after)
    }

    /// The line of the `i`-th joint's first `element`, or of the joint's start tag when it has
    /// none.
    pub(super) fn line(&self, i: usize, element: &str) -> usize {
        let at = self
            .element(i, element)
            .map_or(self.joints[i].tag.start, |s| s.start);
        line_of(&self.text, at)
    }

    /// Refuses the `i`-th joint, a moving joint of the chain to `tip`, at the line of its
    /// `<mimic>` if it has one: calbench does not model a joint coupled to another.
    pub(super) fn uncoupled(&self, path: &Path, i: usize, tip: &str) -> Result<()> {
        let Some((at, other)) = &self.joints[i].mimic else {
            return Ok(());
        };
        let msg = format!(
            "joint \"{}\" on the chain to \"{tip}\" mimics joint \"{other}\": calbench reads \
             each moving joint of the chain as a variable of its own and does not model a joint \
             coupled to another (a parallelogram's, a gripper finger's); a tool on a finger is \
             read with ",
            self.joints[i].name
        );
        let msg = Said::from(msg)
            .name(Opt::Tip)
            .text(" naming a link before it");
        let line = format!("line {}", line_of(&self.text, *at));
        Err(Error::file(path, line, msg))
    }

    /// The text with the `<origin>` of the `i`-th joint set to each `(i, frame)` of
    /// `origins` (added after the joint's start tag where it has none) and `added`, whole
    /// lines of elements, written before the robot's end tag.
    pub(super) fn with(&self, origins: &[(usize, Frame)], added: &str) -> String {
        let t = &self.text;
        let mut edits: Vec<(Range<usize>, String)> = origins
            .iter()
            .map(|(i, f)| {
                let span = self.origin(*i);
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
