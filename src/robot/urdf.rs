//! URDF robots in and out (docs/formats.md, "URDF robots").
//!
//! A URDF's serial chain, from its root link to its only leaf link ([`leaf_links`]; or, in a tree,
//! from the link [`UrdfChain::base`] names to the link [`UrdfChain::tip`] names), becomes a
//! calbench robot in the standard DH convention (Li 2018 eq. 1) by the common-normal construction
//! of Denavit and Hartenberg: at q = 0 every moving joint is a line (its origin and axis in the
//! root frame); frame i−1 has its z axis on joint i's line and its x axis on the common normal of
//! lines i−1 and i (for parallel lines: the perpendicular from the previous origin), which gives θ,
//! d, a, α of every link (Hayati's d = 0 and β where lines a hair from parallel put the common
//! normal beyond ten times the chain's length; the robot is then `dh_beta`). The last link
//! keeps θ = d = a = α = 0, so the whole placement of the tip link after the last joint is the
//! `[tool]` frame; the placement of the first joint's line in the root frame is the `[base]`
//! frame. Joint values are the URDF's: radians for revolute and continuous joints, metres for
//! prismatic ones (the robot's units are rad and m); measured positions stay in mm.
//!
//! Only the elements calbench reads are parsed ([`read`]). Writing back ([`UrdfRobot::write`])
//! keeps the source text, every element and comment of it, and changes only the `<origin>` of
//! each moving joint and of the last fixed joint before the tip (one is added when the tip is
//! a moving joint's child), so that the URDF's FK equals the identified robot's: joint i's
//! frame is the identified DH frame i−1 times the same constant offset as in the source (a
//! turn about and a shift along the joint axis).

mod text;

use std::path::Path;

use crate::error::{Error, Opt, Result, Said};
use crate::numeric::{rot_x, rot_y, rot_z, rpy_matrix, Frame, Real, Vec3};
use crate::robot::{
    to_internal, value_count, AngleUnit, Convention, Joint, JointType, LengthUnit, Param, Quantity,
    Robot, Units, MAX_JOINTS, MAX_LENGTH_MM,
};

/// The fixed joint and link [`UrdfRobot::write`] adds when the tip is a moving joint's child.
const ADDED_TOOL: &str = "calbench_tool";

/// A robot read from a URDF: the calbench robot and what is needed to write it back.
#[derive(Clone, Debug)]
pub struct UrdfRobot {
    /// The calbench robot (standard DH, with Hayati's β on links of nearly parallel axes;
    /// units rad and m).
    pub robot: Robot,
    source: urdf_rs::Robot,
    /// The source's text, which [`UrdfRobot::write`] writes back.
    text: text::Source,
    /// Indices into `source.joints` of the chain, root to tip.
    chain: Vec<usize>,
    /// Per moving joint: DH frame i−1 → the URDF joint frame (constant).
    offsets: Vec<Frame>,
}

/// `<origin>` of a URDF joint as a frame (mm).
fn origin(j: &urdf_rs::Joint) -> Frame {
    let p = &j.origin;
    Frame {
        rot: rpy_matrix(*p.rpy),
        pos: Vec3::new(p.xyz[0], p.xyz[1], p.xyz[2]) * 1000.0,
    }
}

/// The URDF at `path` as urdf-rs parses the elements calbench reads: the robot's name, its
/// links' names and its joints' `<origin>`, `<parent>`, `<child>`, `<axis>` and `<limit>`.
/// Every other element (visuals, collisions, inertials, materials, transmissions, …) is set
/// aside unparsed, so that one urdf-rs refuses (a `<visual>` with two `<material>` elements)
/// does not refuse the robot; it is not in the result.
pub fn read(path: &Path) -> Result<urdf_rs::Robot> {
    text::read(path).map(|(robot, _)| robot)
}

/// The numbers calbench reads of the URDF joint `j` (moving as `kind`), checked as a robot
/// file's are after their conversion to mm and rad ([`to_internal`]): the origin's `xyz`
/// lengths (m) within ±1 km and `rpy` angles within one turn, a moving joint's axis finite,
/// and its limits (but a continuous joint's, which calbench does not read) within range. A
/// refusal names the joint and the element, and is returned with the element's name (for its
/// line).
fn check_numbers(
    j: &urdf_rs::Joint,
    kind: Option<JointType>,
) -> std::result::Result<(), (&'static str, String)> {
    let at = |element: &'static str, key: &str, m: String| {
        let key = if key.is_empty() {
            String::new()
        } else {
            format!(" {key}")
        };
        (
            element,
            format!("joint \"{}\", <{element}{key}>: {m}", j.name),
        )
    };
    for &v in j.origin.xyz.iter() {
        to_internal(Quantity::Length, v, 1000.0, "m").map_err(|m| at("origin", "xyz", m))?;
    }
    for &v in j.origin.rpy.iter() {
        to_internal(Quantity::Angle, v, 1.0, "rad").map_err(|m| at("origin", "rpy", m))?;
    }
    let Some(kind) = kind else { return Ok(()) };
    let a = &j.axis.xyz;
    if !Vec3::new(a[0], a[1], a[2]).norm().is_finite() {
        let msg = format!(
            "must be a direction of finite length, got {:?}",
            [a[0], a[1], a[2]]
        );
        return Err(at("axis", "xyz", msg));
    }
    if j.joint_type != urdf_rs::JointType::Continuous {
        let (quantity, factor, unit) = match kind {
            JointType::Prismatic => (Quantity::Length, 1000.0, "m"),
            JointType::Revolute => (Quantity::JointAngle, 1.0, "rad"),
        };
        for v in [j.limit.lower, j.limit.upper] {
            to_internal(quantity, v, factor, unit).map_err(|m| at("limit", "", m))?;
        }
    }
    Ok(())
}

fn moving(j: &urdf_rs::Joint) -> Result<Option<JointType>> {
    use urdf_rs::JointType as U;
    Ok(match j.joint_type {
        U::Fixed => None,
        U::Revolute | U::Continuous => Some(JointType::Revolute),
        U::Prismatic => Some(JointType::Prismatic),
        // The file's spelling (`floating`), not the Rust variant's (`Floating`).
        _ => {
            let kind = format!("{:?}", j.joint_type).to_lowercase();
            return Err(Error::Compute(not_one_axis(&j.name, &kind)));
        }
    })
}

/// The joint types calbench reads, as a URDF spells them.
const ONE_AXIS: [&str; 4] = ["revolute", "continuous", "prismatic", "fixed"];

/// URDF's other joint types: a file may hold them off the chain calbench reads (a mobile
/// base's `floating` joint above `--base`, a sensor on another branch), and [`moving`] refuses
/// one on the chain.
const OFF_CHAIN: [&str; 2] = ["floating", "planar"];

/// The refusal of joint `name` of type `kind`, which is none of [`ONE_AXIS`] (a URDF type
/// such as `planar`, or none at all: URDF's other types are not offered as a choice).
fn not_one_axis(name: &str, kind: &str) -> String {
    format!(
        "joint \"{name}\": type {kind} is not a one-axis joint ({})",
        ONE_AXIS.join(", ")
    )
}

/// Hayati's turn Ry(β) that ends a `dh_beta` link.
fn turn_y(beta: Real) -> Frame {
    Frame {
        rot: rot_y(beta),
        pos: Vec3::zeros(),
    }
}

/// The DH link transform Rz(θ)Tz(d)Tx(a)Rx(α).
fn dh(theta: Real, d: Real, a: Real, alpha: Real) -> Frame {
    let rz = rot_z(theta);
    Frame {
        rot: rz * rot_x(alpha),
        pos: rz * Vec3::new(a, 0.0, 0.0) + Vec3::new(0.0, 0.0, d),
    }
}

/// The parameters (θ, d, a, α, β) of the link from frame `prev` (z on the previous joint's
/// line) to the frame whose z is on the line (`p`, `u`), and that frame: DH's (β = 0), or,
/// where DH's d or a is beyond `far` mm (lines a hair from parallel, whose common normal runs
/// off to kilometres and whose d the data can hardly determine), Hayati's form (Qiao 2021
/// eq. 1): d = 0, x along the perpendicular from the previous origin to the line, and the rest
/// of the turn onto the line as `Ry(β)`.
fn next_frame(prev: &Frame, p: &Vec3, u: &Vec3, far: Real) -> ([Real; 5], Frame) {
    let (dh_values, f) = dh_frame(prev, p, u);
    if dh_values[1].abs() <= far && dh_values[2].abs() <= far {
        let [theta, d, a, alpha] = dh_values;
        return ([theta, d, a, alpha, 0.0], f);
    }
    let (o0, z0, x0) = (
        prev.pos,
        prev.rot.column(2).into_owned(),
        prev.rot.column(0).into_owned(),
    );
    // The point of the line level with the previous origin along z0 (the lines are nearly
    // parallel, so u·z0 is near 1).
    let r = p + ((o0 - p).dot(&z0) / u.dot(&z0)) * u - o0;
    let x1 = if r.norm() > 1e-9 { r.normalize() } else { x0 };
    let y1 = z0.cross(&x1);
    let theta = x0.cross(&x1).dot(&z0).atan2(x0.dot(&x1));
    let a = r.dot(&x1);
    // Rx(α) Ry(β) ẑ = (sin β, −sin α cos β, cos α cos β) = u in (x1, y1, z0).
    let (ux, uy, uz) = (u.dot(&x1), u.dot(&y1), u.dot(&z0));
    let alpha = (-uy).atan2(uz);
    let beta = ux.atan2((uy * uy + uz * uz).sqrt());
    let f = prev
        .compose(&dh(theta, 0.0, a, alpha))
        .compose(&turn_y(beta));
    ([theta, 0.0, a, alpha, beta], f)
}

/// The DH parameters (θ, d, a, α) of [`next_frame`]'s link by the common normal, and the
/// frame they give.
fn dh_frame(prev: &Frame, p: &Vec3, u: &Vec3) -> ([Real; 4], Frame) {
    let (o0, z0, x0) = (
        prev.pos,
        prev.rot.column(2).into_owned(),
        prev.rot.column(0).into_owned(),
    );
    let n = z0.cross(u);
    let (foot0, o1, x1) = if n.norm() > 1e-9 {
        // Closest points of the lines o0 + s z0 and p + t u.
        let w = o0 - p;
        let (b, d, e) = (z0.dot(u), z0.dot(&w), u.dot(&w));
        let den = 1.0 - b * b;
        let s = (b * e - d) / den;
        let t = (e - b * d) / den;
        (o0 + s * z0, p + t * u, n.normalize())
    } else {
        // Parallel: the perpendicular from the previous origin.
        let o1 = p + (o0 - p).dot(u) * u;
        let r = o1 - o0;
        let x = if r.norm() > 1e-9 { r.normalize() } else { x0 };
        (o0, o1, x)
    };
    let d = (foot0 - o0).dot(&z0);
    let a = (o1 - foot0).dot(&x1);
    let theta = x0.cross(&x1).dot(&z0).atan2(x0.dot(&x1));
    let alpha = z0.cross(u).dot(&x1).atan2(z0.dot(u));
    let f = prev.compose(&dh(theta, d, a, alpha));
    ([theta, d, a, alpha], f)
}

/// Which chain of a URDF tree is the robot (`--base LINK`, `--tip LINK`); by default from the
/// root link to the only leaf link ([`leaf_links`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UrdfChain {
    /// The link the chain starts at (its frame is the robot's base); `None`: the root.
    pub base: Option<String>,
    /// The link the chain ends at (the tool's link); `None`: the only leaf.
    pub tip: Option<String>,
}

/// The links of `urdf` a chain can end at: the links no joint leaves from, less those that
/// hang from the root through fixed joints alone (a frame such as ROS-Industrial's `base`,
/// which no joint moves, cannot be a tool's link). When every leaf hangs so, all of them.
pub fn leaf_links(urdf: &urdf_rs::Robot) -> Vec<&str> {
    let parents: std::collections::HashSet<&str> =
        urdf.joints.iter().map(|j| j.parent.link.as_str()).collect();
    let leaves: Vec<&str> = urdf
        .joints
        .iter()
        .map(|j| j.child.link.as_str())
        .filter(|c| !parents.contains(c))
        .collect();
    // Whether a joint that is not fixed stands between `leaf` and the root (a loop, refused
    // when the chain is read, ends the walk).
    let joint_to = text::child_joints(urdf);
    let moved = |leaf: &str| {
        let mut joint = joint_to.get(leaf).copied();
        for _ in 0..urdf.joints.len() {
            let Some(j) = joint.map(|i| &urdf.joints[i]) else {
                return false;
            };
            if j.joint_type != urdf_rs::JointType::Fixed {
                return true;
            }
            joint = joint_to.get(j.parent.link.as_str()).copied();
        }
        false
    };
    let tips: Vec<&str> = leaves.iter().copied().filter(|l| moved(l)).collect();
    if tips.is_empty() {
        leaves
    } else {
        tips
    }
}

impl UrdfRobot {
    /// Reads the URDF at `path`: the chain from the root link to the only leaf link
    /// ([`leaf_links`]).
    pub fn load(path: &Path) -> Result<UrdfRobot> {
        Self::load_chain(path, &UrdfChain::default())
    }

    /// Reads the URDF at `path`: the chain `which` chooses. Fails when the tree has several
    /// leaves and no tip is named, a named link does not exist, or the base is not on the
    /// way from the root to the tip.
    pub fn load_chain(path: &Path, which: &UrdfChain) -> Result<UrdfRobot> {
        let bad = |msg: String| Error::file(path, "URDF", msg);
        let said = |msg: Said| Error::file(path, "URDF", msg);
        let (source, text) = text::read(path)?;
        let js = &source.joints;
        let leaves = leaf_links(&source);
        let known = |l: &str| source.links.iter().any(|k| k.name == l);
        for (key, l) in [(Opt::Base, &which.base), (Opt::Tip, &which.tip)] {
            if let Some(l) = l.as_deref().filter(|l| !known(l)) {
                let msg = format!(": no link \"{l}\" in the URDF");
                return Err(said(Said::default().name(key).text(msg)));
            }
        }
        let tip = match (&which.tip, leaves.as_slice()) {
            (Some(t), _) => t.as_str(),
            (None, [one]) => one,
            (None, []) if source.links.is_empty() => {
                return Err(bad("the robot has no <link>".into()))
            }
            (None, []) => return Err(bad("the chain has no moving joint".into())),
            (None, _) => {
                let msg = format!(
                    "{} leaf links ({}): calbench takes a serial chain to one tip link; name \
                     it with ",
                    leaves.len(),
                    leaves.join(", ")
                );
                return Err(said(Said::from(msg).name(Opt::Tip).text(" LINK")));
            }
        };
        // The tool a written URDF added after a tip that is a moving joint's child
        // ([`UrdfRobot::write`]) ends the chain that tip names, so that `--tip` names the same
        // chain in the nominal URDF and in the identified one.
        let tip = js
            .iter()
            .find(|j| j.name == ADDED_TOOL && j.parent.link == tip && j.child.link == ADDED_TOOL)
            .map_or(tip, |j| j.child.link.as_str());
        let mut chain = Vec::new();
        let mut link = tip;
        let joint_to = text::child_joints(&source);
        let mut walked = vec![false; js.len()];
        while which.base.as_deref() != Some(link) {
            let Some(&i) = joint_to.get(link) else {
                if let Some(b) = &which.base {
                    let msg =
                        format!(": link \"{b}\" is not on the chain from the root to \"{tip}\"");
                    return Err(said(Said::default().name(Opt::Base).text(msg)));
                }
                break;
            };
            if walked[i] || chain.len() > js.len() {
                return Err(bad(format!("the joints form a loop at link \"{link}\"")));
            }
            walked[i] = true;
            chain.push(i);
            link = js[i].parent.link.as_str();
        }
        chain.reverse();
        // The moving joints' frames and axes at q = 0, in the root frame.
        let mut w = Frame::identity();
        let mut lines = Vec::new();
        let mut joints = Vec::new();
        for &i in &chain {
            let j = &js[i];
            // A refusal of the joint's `element` (its start tag for `joint`), on its line.
            let at = |element: &str, msg: String| {
                Error::file(path, format!("line {}", text.line(i, element)), msg)
            };
            let kind = moving(j).map_err(|e| at("joint", e.to_string()))?;
            check_numbers(j, kind).map_err(|(element, msg)| at(element, msg))?;
            w = w.compose(&origin(j));
            if let Some(kind) = kind {
                text.uncoupled(path, i, tip)?;
                if joints.len() == MAX_JOINTS {
                    let msg = format!(
                        "joint \"{}\" is moving joint {} of the chain to \"{tip}\": at most \
                         {MAX_JOINTS} moving joints are supported",
                        j.name,
                        MAX_JOINTS + 1
                    );
                    return Err(at("joint", msg));
                }
                let a = Vec3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
                if a.norm().partial_cmp(&1e-12) != Some(std::cmp::Ordering::Greater) {
                    return Err(at("axis", format!("joint \"{}\": zero axis", j.name)));
                }
                let scale = if kind == JointType::Prismatic {
                    1000.0
                } else {
                    1.0
                };
                let limits = if j.joint_type == urdf_rs::JointType::Continuous {
                    (-2.0 * std::f64::consts::PI, 2.0 * std::f64::consts::PI)
                } else {
                    (j.limit.lower * scale, j.limit.upper * scale)
                };
                if limits.0.partial_cmp(&limits.1) != Some(std::cmp::Ordering::Less) {
                    return Err(at(
                        "limit",
                        format!(
                            "joint \"{}\": limits [{}, {}] are not an interval (a revolute \
                             or prismatic joint needs <limit lower upper> with lower < upper; \
                             a missing <limit> reads as [0, 0])",
                            j.name, j.limit.lower, j.limit.upper
                        ),
                    ));
                }
                joints.push(Joint { kind, limits });
                lines.push((w, w.rot * a.normalize()));
            }
        }
        let n = joints.len();
        if n == 0 {
            return Err(bad("the chain has no moving joint".into()));
        }
        // Frame 0: on the first line, x perpendicular to it.
        let (w1, u1) = lines[0];
        let helper = if u1.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        let x0 = (helper - helper.dot(&u1) * u1).normalize();
        let base = Frame {
            rot: crate::numeric::Mat3::from_columns(&[x0, u1.cross(&x0), u1]),
            pos: w1.pos,
        };
        let mut values = vec![0.0; value_count(n)];
        let mut frame = base;
        let mut offsets = Vec::with_capacity(n);
        // The links given Hayati's β ([`next_frame`]): those whose DH length would be beyond
        // ten times the chain's own length (the sum of its joints' offsets), or a robot
        // file's range.
        let mut betas = Vec::new();
        let length: Real = chain.iter().map(|&i| origin(&js[i]).pos.norm()).sum();
        let far = (10.0 * length).clamp(1.0, MAX_LENGTH_MM);
        for k in 0..n {
            offsets.push(frame.inverse().compose(&lines[k].0));
            if k + 1 < n {
                let (wp, u) = lines[k + 1];
                let (p, f) = next_frame(&frame, &wp.pos, &u, far);
                let link = [Param::Theta(k), Param::D(k), Param::A(k), Param::Alpha(k)];
                for (c, v) in link.into_iter().chain([Param::Beta(k)]).zip(p) {
                    values[c.index(n)] = v;
                }
                if p[4] != 0.0 {
                    betas.push(k);
                }
                frame = f;
            }
        }
        // The tip at q = 0 seen from the last DH frame (= frame n−1 at q = 0).
        let tool = frame.inverse().compose(&w);
        let (bx, br) = base.to_xyz_rpy();
        let (tx, tr) = tool.to_xyz_rpy();
        for c in 0..3 {
            values[Param::Base(c).index(n)] = bx[c];
            values[Param::Base(3 + c).index(n)] = br[c];
            values[Param::Tool(c).index(n)] = tx[c];
            values[Param::Tool(3 + c).index(n)] = tr[c];
        }
        let robot = Robot {
            name: source.name.clone(),
            convention: match betas.is_empty() {
                true => Convention::Dh,
                false => Convention::DhBeta,
            },
            joints,
            values,
            units: Units {
                length: LengthUnit::M,
                angle: AngleUnit::Rad,
            },
            coupling: None,
            beta_joints: (!betas.is_empty()).then_some(betas),
            link_mass_kg: None,
        };
        // Origins within range can still add up beyond it (a base 3 km from the root).
        robot.check().map_err(|i| {
            bad(format!(
                "the robot the chain makes: {}: {} (the DH values and frames calbench derives \
                 from the joints' origins and axes)",
                i.place, i.msg
            ))
        })?;
        Ok(UrdfRobot {
            robot,
            source,
            text,
            chain,
            offsets,
        })
    }

    /// The source URDF with its joint origins moved so that its FK is `identified`'s (a
    /// robot with this robot's joints, e.g. the compensated robot of `identify`).
    pub fn write(&self, identified: &Robot) -> Result<String> {
        let n = self.robot.dof();
        let js = &self.source.joints;
        // DH frames i−1 at q = 0 (without the tool): the frames of the moving joints.
        let mut frames = Vec::with_capacity(n);
        let mut f = identified.base();
        let v = |p: Param| identified.get(p);
        for k in 0..n {
            frames.push(f);
            f = f.compose(&dh(
                v(Param::Theta(k)),
                v(Param::D(k)),
                v(Param::A(k)),
                v(Param::Alpha(k)),
            ));
            if identified.carries_beta(k) {
                f = f.compose(&turn_y(v(Param::Beta(k))));
            }
        }
        let tip = f.compose(&identified.tool());
        let mut w = Frame::identity(); // the source's frames, updated as joints move
        let mut k = 0;
        let mut last_fixed = None;
        // The new origin of each joint moved (its index in the source's joints).
        let mut origins = Vec::with_capacity(n + 1);
        for (pos, &i) in self.chain.iter().enumerate() {
            let j = &js[i];
            if moving(j)?.is_some() {
                let target = frames[k].compose(&self.offsets[k]);
                origins.push((i, w.inverse().compose(&target)));
                w = target;
                k += 1;
                last_fixed = None;
            } else {
                w = w.compose(&origin(j));
                if k == n {
                    last_fixed = Some(pos);
                }
            }
        }
        // The placement of the tip after the last moving joint.
        let before_last = match last_fixed {
            Some(pos) => w.compose(&origin(&js[self.chain[pos]]).inverse()),
            None => w,
        };
        let place = before_last.inverse().compose(&tip);
        let added = match last_fixed {
            Some(pos) => {
                origins.push((self.chain[pos], place));
                String::new()
            }
            None => {
                let parent = &js[*self.chain.last().unwrap_or(&0)].child.link;
                let (name, parent) = (ADDED_TOOL, xml_attribute(parent));
                joint_element(name, "fixed", &parent, name, &place, None)
            }
        };
        Ok(self.text.with(&origins, &added))
    }
}

/// `text` as the value of an XML attribute in double quotes: `&`, `<`, `>`, `"` and `'` as
/// entities, and the control characters an attribute would not keep (tab, line breaks) as
/// character references, so that a reader gives back `text` itself (XML 1.0 §§ 2.4, 3.3.3).
pub fn xml_attribute(text: &str) -> String {
    let s = quick_xml::escape::escape(text);
    s.replace('\t', "&#9;")
        .replace('\n', "&#10;")
        .replace('\r', "&#13;")
}

/// A `<link>` named `child` and the `<joint>` `name` of type `kind` from `parent` to it, its
/// origin the frame `o` (mm) and, with `lim` (in the URDF's units), the z axis and those
/// limits: lines indented as children of `<robot>`. The names are written as given (escaped,
/// where they need it, by the caller).
fn joint_element(
    name: &str,
    kind: &str,
    parent: &str,
    child: &str,
    o: &Frame,
    lim: Option<(Real, Real)>,
) -> String {
    let mut s = format!(
        "  <link name=\"{child}\"/>\n  <joint name=\"{name}\" type=\"{kind}\">\n    <parent link=\"{parent}\"/>\n    <child link=\"{child}\"/>\n    {}\n",
        text::origin_element(o)
    );
    if let Some((lo, hi)) = lim {
        s.push_str(&format!(
            "    <axis xyz=\"0 0 1\"/>\n    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>\n",
            text::number(lo),
            text::number(hi)
        ));
    }
    s + "  </joint>\n"
}

/// Whether `robot` names a URDF file: by its extension `.urdf`, or a file whose text begins
/// with `<` (XML under another name, `.xml` as ROS tools write it; no TOML file begins so).
pub fn is_urdf(robot: impl AsRef<Path>) -> bool {
    let path = robot.as_ref();
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
        || begins_as_xml(path)
}

/// Whether the file `path` begins, past a byte-order mark and white space, with `<`; `false`
/// for a file that cannot be read (its reader names why).
fn begins_as_xml(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 256];
    let Ok(n) = std::fs::File::open(path).and_then(|mut f| f.read(&mut head)) else {
        return false;
    };
    let head = head[..n]
        .strip_prefix(b"\xEF\xBB\xBF")
        .unwrap_or(&head[..n]);
    head.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'<')
}

/// A URDF of a calbench robot (`identify --export urdf` on a robot file): root link `world`, a
/// fixed joint `base_placement` to `base_link` (the `[base]` frame), joint i (`joint_i`, child
/// `link_i`) turning or sliding along the z axis of its frame, whose origin holds what of the
/// link transforms lies between joints i−1 and i, a fixed joint to `flange` with the rest of the
/// last link and one to `tcp` with the `[tool]` frame. Lengths in m, angles in rad.
pub fn robot_to_urdf(robot: &Robot) -> Result<String> {
    if robot.coupling.is_some() {
        return Err(Error::option(
            Opt::Export,
            "urdf: a robot with an actuator coupling has no URDF form",
        ));
    }
    let v = |p: Param| robot.get(p);
    let ry = |b: Real| Frame {
        rot: crate::numeric::rot_y(b),
        pos: Vec3::zeros(),
    };
    let rz = |t: Real| Frame {
        rot: rot_z(t),
        pos: Vec3::zeros(),
    };
    let tz = |d: Real| Frame {
        rot: crate::numeric::Mat3::identity(),
        pos: Vec3::new(0.0, 0.0, d),
    };
    let xa = |alpha: Real, a: Real| Frame {
        rot: rot_x(alpha),
        pos: Vec3::new(a, 0.0, 0.0),
    };
    let mut s = format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"{}\">\n  <link name=\"world\"/>\n",
        xml_attribute(&robot.name)
    );
    s += &joint_element(
        "base_placement",
        "fixed",
        "world",
        "base_link",
        &robot.base(),
        None,
    );
    let mut post = Frame::identity();
    let mut parent = "base_link".to_string();
    for (k, j) in robot.joints.iter().enumerate() {
        let (th, d, a, al, be) = (
            v(Param::Theta(k)),
            v(Param::D(k)),
            v(Param::A(k)),
            v(Param::Alpha(k)),
            v(Param::Beta(k)),
        );
        let rev = j.kind == JointType::Revolute;
        let (pre, next) = match robot.convention {
            Convention::Dh | Convention::DhBeta => {
                let tail = tz(d).compose(&xa(al, a)).compose(&ry(be));
                if rev {
                    (Frame::identity(), rz(th).compose(&tail))
                } else {
                    (rz(th), tail)
                }
            }
            Convention::Mdh => {
                let head = xa(al, 0.0).compose(&Frame {
                    rot: crate::numeric::Mat3::identity(),
                    pos: Vec3::new(a, 0.0, 0.0),
                });
                if rev {
                    (head.compose(&rz(th)), tz(d).compose(&ry(be)))
                } else {
                    (head.compose(&rz(th)).compose(&tz(d)), ry(be))
                }
            }
        };
        let (kind, scale) = if rev {
            ("revolute", 1.0)
        } else {
            ("prismatic", 1e-3)
        };
        let child = format!("link_{}", k + 1);
        s += &joint_element(
            &format!("joint_{}", k + 1),
            kind,
            &parent,
            &child,
            &post.compose(&pre),
            Some((j.limits.0 * scale, j.limits.1 * scale)),
        );
        parent = child;
        post = next;
    }
    s += &joint_element("flange_fixed", "fixed", &parent, "flange", &post, None);
    s += &joint_element("tool_fixed", "fixed", "flange", "tcp", &robot.tool(), None);
    s.push_str("</robot>\n");
    Ok(s)
}
