//! The HTML pages (`report.html` of run, sweeps and identify; `compare.html`) opened in
//! headless Chromium: no console error, no request to any file or host, every plot drawn with
//! a non-zero size, no sideways scrolling at phone width (500 px), and a screenshot that is not blank.
//! Without Chromium the browser part says that it was skipped; with `CI=true` it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

use crate::common::{
    calbench_ok, load_json, path_arg, read, root, tmp_dir, write_scenario, SMALL_STUDY as SMALL,
};

pub(crate) fn ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}

/// Debian's `chromium` (or another Chromium build on the PATH).
pub(crate) fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |d| d.join(name)))
        .find(|p| p.is_file())
}

/// Loads the page in Chromium with a probe added at the top of its head: a content security
/// policy that blocks (and reports) every request, and a script that records console errors,
/// uncaught errors, blocked requests, loaded resources, the size of every `<svg>` and the
/// page's scroll width, and writes them as JSON into the DOM that `--dump-dom` prints.
fn probe(chrome: &Path, page: &Path, width: u32, work: &Path) -> Value {
    const PROBE: &str = r#"<meta http-equiv="Content-Security-Policy" content="default-src 'none'; style-src 'unsafe-inline'; script-src 'unsafe-inline'">
<script>
window.__probe={errors:[],blocked:[]};
(function(){var p=window.__probe,e=console.error;
console.error=function(){p.errors.push(Array.prototype.join.call(arguments,' '));e.apply(console,arguments);};
window.addEventListener('error',function(ev){p.errors.push('uncaught: '+(ev.message||(ev.target&&(ev.target.src||ev.target.href))||'?'));},true);
document.addEventListener('securitypolicyviolation',function(ev){p.blocked.push(ev.blockedURI+' ('+ev.violatedDirective+')');});
window.addEventListener('load',function(){setTimeout(function(){
var svgs=Array.prototype.map.call(document.querySelectorAll('svg'),function(s){var r=s.getBoundingClientRect();return [r.width,r.height];});
var broken=[],walk=document.createTreeWalker(document.body,NodeFilter.SHOW_TEXT),node;
while((node=walk.nextNode())){if(node.parentNode.closest('svg,script,style,pre'))continue;
var re=/(?<![\w.\u2212-])[-\u2212]?\d[\d.]*(?:e[-+\u2212]?\d+)?%?/g,m;while((m=re.exec(node.data))){var rg=document.createRange();
rg.setStart(node,m.index);rg.setEnd(node,m.index+m[0].length);var tops={};
Array.prototype.forEach.call(rg.getClientRects(),function(r){if(r.width>0)tops[Math.round(r.top)]=1;});
if(Object.keys(tops).length>1)broken.push(m[0]);}}
var out={errors:p.errors,blocked:p.blocked,svgs:svgs,broken:broken,
headings:Array.prototype.map.call(document.querySelectorAll('h2'),function(h){return h.textContent;}),
labels:Array.prototype.map.call(document.querySelectorAll('svg'),function(s){return Array.prototype.map.call(s.querySelectorAll('text'),function(t){return t.textContent.trim();});}),
resources:performance.getEntriesByType('resource').map(function(r){return r.name;}),
scrollWidth:document.documentElement.scrollWidth,innerWidth:window.innerWidth};
var pre=document.createElement('pre');pre.id='calbench-probe';pre.textContent=JSON.stringify(out);document.body.appendChild(pre);},50);});})();
</script>"#;
    let html = read(page);
    let at = html.find("<head>").expect("the page has a <head>") + "<head>".len();
    let probed = work.join(format!("probe-{width}.html"));
    std::fs::write(&probed, format!("{}{PROBE}{}", &html[..at], &html[at..])).unwrap();
    let out = Command::new(chrome)
        .args(chrome_args(work, width))
        .args(["--dump-dom", "--virtual-time-budget=5000"])
        .arg(format!("file://{}", probed.display()))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&out.stdout);
    let json = dom
        .split("<pre id=\"calbench-probe\">")
        .nth(1)
        .and_then(|s| s.split("</pre>").next())
        .unwrap_or_else(|| {
            panic!(
                "{}: no probe result in Chromium's DOM:\n{}",
                page.display(),
                String::from_utf8_lossy(&out.stderr)
            )
        })
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    // The console as Chromium logs it: an uncaught error or a blocked request.
    let stderr = String::from_utf8_lossy(&out.stderr);
    let logged: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains(":CONSOLE") && (l.contains("Uncaught") || l.contains("violates")))
        .collect();
    assert!(logged.is_empty(), "{}: console: {logged:?}", page.display());
    serde_json::from_str(&json).unwrap()
}

/// The command-line options of every Chromium start: headless, a profile of its own.
fn chrome_args(work: &Path, width: u32) -> Vec<String> {
    vec![
        "--headless".into(),
        "--no-sandbox".into(),
        "--disable-gpu".into(),
        "--hide-scrollbars".into(),
        "--no-first-run".into(),
        "--enable-logging=stderr".into(),
        "--v=0".into(),
        format!(
            "--user-data-dir={}",
            work.join(format!("profile-{width}")).display()
        ),
        format!("--window-size={width},1400"),
    ]
}

/// A screenshot of the page at 1280 px: the share of pixels that are not white and the
/// number of distinct colours.
fn screenshot(chrome: &Path, page: &Path, work: &Path) -> (f64, usize) {
    let shot = work.join("shot.png");
    let _ = std::fs::remove_file(&shot);
    let out = Command::new(chrome)
        .args(chrome_args(work, 1280))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap();
    assert!(
        shot.is_file(),
        "{}: Chromium wrote no screenshot:\n{}",
        page.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples();
    let pixels: Vec<&[u8]> = buf[..info.buffer_size()].chunks(px).collect();
    let inked = pixels
        .iter()
        .filter(|p| p[..3].iter().any(|c| *c < 235))
        .count();
    let colours: std::collections::HashSet<&[u8]> = pixels.iter().copied().collect();
    (inked as f64 / pixels.len() as f64, colours.len())
}

/// The static checks of a page: one file that refers to nothing outside itself, under 3 MB.
pub(crate) fn self_contained(page: &Path) -> String {
    let html = read(page);
    for attr in ["src=", "href=", "url("] {
        for (i, _) in html.match_indices(attr) {
            let rest = html[i + attr.len()..].trim_start_matches(['"', '\'', ' ']);
            assert!(
                rest.starts_with('#') || rest.starts_with("data:"),
                "{}: refers to another file or host: {}",
                page.display(),
                &html[i..(i + 80).min(html.len())]
            );
        }
    }
    assert!(
        html.len() < 3_000_000,
        "{}: {} bytes",
        page.display(),
        html.len()
    );
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    html
}

/// The tick labels of a plot that are the tick arithmetic's residue where 0 belongs (such
/// as −2.78e-17 on an axis from −0.18 to 0.02): a label within 10⁻⁹ of the largest of a
/// plot whose labels hold a negative value (a logarithmic axis holds none).
pub(crate) fn residues_of_zero(labels: &[String]) -> Vec<String> {
    let values: Vec<f64> = labels
        .iter()
        .filter_map(|l| l.replace('\u{2212}', "-").parse::<f64>().ok())
        .collect();
    let largest = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !values.iter().any(|v| *v < 0.0) {
        return Vec::new();
    }
    labels
        .iter()
        .filter(|l| {
            l.replace('\u{2212}', "-")
                .parse::<f64>()
                .is_ok_and(|v| v != 0.0 && v.abs() < 1e-9 * largest)
        })
        .cloned()
        .collect()
}

/// Opens `page` in Chromium at 1280 and 500 px and checks it ([`probe`]): no console error,
/// no request, `plots` plots of a real size, no sideways scrolling, at 1280 px no number
/// broken over two lines, no tick label that is a residue of 0 ([`residues_of_zero`]), a
/// screenshot that is not blank. Gives the section headings in page order.
pub(crate) fn browse(chrome: &Path, page: &Path, work: &Path, plots: usize) -> Vec<String> {
    std::fs::create_dir_all(work).unwrap();
    let mut headings = Vec::new();
    // 500 px: the narrowest window headless Chromium lays out (a phone's width).
    for width in [1280, 500] {
        let p = probe(chrome, page, width, work);
        let name = format!("{} at {width} px", page.display());
        if width == 1280 {
            assert_eq!(
                p["broken"],
                Value::Array(vec![]),
                "{name}: numbers broken over lines"
            );
            headings = serde_json::from_value(p["headings"].clone()).unwrap();
            for labels in p["labels"].as_array().unwrap() {
                let labels: Vec<String> = serde_json::from_value(labels.clone()).unwrap();
                let bad = residues_of_zero(&labels);
                assert!(
                    bad.is_empty(),
                    "{name}: tick labels {bad:?} where 0 belongs"
                );
            }
        }
        assert_eq!(p["errors"], Value::Array(vec![]), "{name}: console errors");
        assert_eq!(p["blocked"], Value::Array(vec![]), "{name}: requests");
        assert_eq!(p["resources"], Value::Array(vec![]), "{name}: requests");
        let svgs = p["svgs"].as_array().unwrap();
        assert_eq!(svgs.len(), plots, "{name}: plots drawn");
        for s in svgs {
            assert!(
                s[0].as_f64().unwrap() > 100.0 && s[1].as_f64().unwrap() > 50.0,
                "{name}: a plot of size {s}"
            );
        }
        assert!(
            p["scrollWidth"].as_f64() <= p["innerWidth"].as_f64(),
            "{name}: the page scrolls sideways ({} > {})",
            p["scrollWidth"],
            p["innerWidth"]
        );
    }
    let (inked, colours) = screenshot(chrome, page, work);
    assert!(
        inked > 0.02 && colours > 40,
        "{}: the screenshot looks blank ({:.3} inked, {colours} colours)",
        page.display(),
        inked
    );
    headings
}

#[test]
fn a_residue_of_zero_among_tick_labels_is_found() {
    let l = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(
        residues_of_zero(&l(&["-0.04", "-0.02", "-2.78e-17", "0.02", "ls / random"])),
        ["-2.78e-17"]
    );
    assert!(residues_of_zero(&l(&["-0.04", "-0.02", "0", "0.02"])).is_empty());
    // A logarithmic axis: small ticks are values.
    assert!(residues_of_zero(&l(&["1e-12", "1e-6", "1"])).is_empty());
}

/// The sections of a run's page in order: the verdicts (the paper's claims, where there are
/// any, then the paired verdicts and the headline figures) before how they were obtained.
fn assert_verdicts_lead(name: &str, headings: &[String], claims: bool) {
    let at = |h: &str| {
        headings
            .iter()
            .position(|x| x == h)
            .unwrap_or_else(|| panic!("{name}: no section {h:?} in {headings:?}"))
    };
    let mut lead = vec!["Paired verdicts", "Headline figures", "Settings", "Results"];
    if claims {
        lead.insert(0, "The paper's claims");
    }
    let order: Vec<usize> = lead.iter().map(|h| at(h)).collect();
    assert_eq!(
        order,
        (0..lead.len()).collect::<Vec<_>>(),
        "{name}: {headings:?}"
    );
}

#[test]
fn every_page_is_self_contained_and_renders_in_chromium() {
    let dir = tmp_dir("cli-html");
    let small = write_scenario(&dir, "small", SMALL);
    let grid = write_scenario(
        &dir,
        "grid",
        &format!(
            "{SMALL}\n[[sweep]]\nkey = \"outliers.count\"\nvalues = [0, 2]\n\
             [[sweep]]\nkey = \"methods.rob.k0\"\nvalues = [1.0, 2.0]\n"
        ),
    );
    let sweep = write_scenario(
        &dir,
        "sweep",
        &format!("{SMALL}\n[sweep]\nkey = \"outliers.count\"\nvalues = [0, 2]\n"),
    );
    let li = root().join("scenarios/li2018-irb2600.toml");
    let mut pages: Vec<(PathBuf, usize)> = Vec::new();
    for (sc, name, trials) in [
        (&small, "run", "2"),
        (&grid, "grid", "2"),
        (&sweep, "sweep", "2"),
        (&li, "li", "8"),
    ] {
        let out = dir.join(name);
        calbench_ok(&[
            "run",
            path_arg(sc),
            "--trials",
            trials,
            "--out",
            path_arg(&out),
        ]);
        let page = out.join("report.html");
        let html = self_contained(&page);
        // One inline plot per SVG file of the run, each with a title and a text alternative.
        let files = std::fs::read_dir(&out)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().path().extension() == Some("svg".as_ref()))
            .count();
        assert!(files >= 3, "{name}: {files} plots");
        assert_eq!(html.matches("<svg").count(), files, "{name}");
        assert_eq!(html.matches("role=\"img\"").count(), files, "{name}");
        assert_eq!(html.matches("<desc ").count(), files, "{name}");
        for section in [
            "Settings",
            "Results",
            "Validation before and after",
            "CRB ratio",
        ] {
            assert!(
                html.contains(&format!(">{section}</h2>")),
                "{name}: {section}"
            );
        }
        assert!(html.contains(">Terminations and failures</h2>"), "{name}");
        // The verdicts lead, in the page's text as in the browser.
        let headings: Vec<String> = html
            .split("<h2 id=\"")
            .skip(1)
            .filter_map(|h| h.split('>').nth(1)?.split('<').next())
            .map(|h| h.replace("&apos;", "'"))
            .collect();
        assert_verdicts_lead(name, &headings, name == "li");
        // No Markdown mark shows as text (the notes' `code` and **strong** are elements).
        let text = html.split("<pre>").next().unwrap();
        assert!(
            !text.contains('`') && !text.contains("**"),
            "{name}: raw Markdown"
        );
        if name == "li" {
            // The paired verdicts' plots carry the interval of the verdict's test.
            assert!(
                html.contains("estimate and 95 % interval of the verdict"),
                "{name}"
            );
        }
        if name == "grid" {
            assert!(html.contains("heatmap") || html.contains("Validation RMS after"));
        }
        pages.push((page, files));
    }
    // identify on simulated data with outliers: the warning about rejected points is there.
    let sim = dir.join("sim");
    calbench_ok(&[
        "simulate",
        path_arg(&small),
        "--trial",
        "0",
        "--out",
        path_arg(&sim),
    ]);
    let id = dir.join("id");
    calbench_ok(&[
        "identify",
        "--robot",
        "irb2600",
        "--data",
        path_arg(&sim.join("measurements.csv")),
        "--validate",
        path_arg(&sim.join("validation.csv")),
        "--method",
        "igg3",
        "--out",
        path_arg(&id),
    ]);
    let page = id.join("report.html");
    let html = self_contained(&page);
    let ident = load_json(&id.join("identified.json"));
    for p in ident["parameters"].as_array().unwrap() {
        assert!(html.contains(&format!("<td class=\"t\">{}</td>", p.as_str().unwrap())));
    }
    assert!(html.contains("rejected as outliers"), "the IGG3 warning");
    assert!(html.contains(&format!(
        "of {} parameters",
        ident["parameters"].as_array().unwrap().len()
    )));
    pages.push((page, 3));
    // compare: a worsened copy is marked, an equal one is not; an entry in one run only is
    // listed as such.
    let a = dir.join("run");
    let mut s = load_json(&a.join("summary.json"));
    let e = &mut s["results"][0];
    e["eta_mean_pct"] = (e["eta_mean_pct"].as_f64().unwrap() - 10.0).into();
    s["results"].as_array_mut().unwrap().pop();
    let b = dir.join("b.json");
    std::fs::write(&b, s.to_string()).unwrap();
    let o = calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&b),
        "--out",
        path_arg(&dir.join("cmp")),
    ]);
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("regressed") && said.contains("1 entries only in A"),
        "{said}"
    );
    let page = dir.join("cmp/compare.html");
    let html = self_contained(&page);
    assert!(html.contains("<tr class=\"regressed\">"));
    assert!(html.contains("A only"));
    let md = read(&dir.join("cmp/compare.md"));
    assert!(
        md.contains("| regression |") && md.contains("A only"),
        "{md}"
    );
    calbench_ok(&[
        "compare",
        path_arg(&a),
        path_arg(&a),
        "--out",
        path_arg(&dir.join("same")),
    ]);
    assert!(!read(&dir.join("same/compare.html")).contains("<tr class=\"regressed\">"));
    // The compare page inlines its plot of the changes.
    assert_eq!(html.matches("<svg").count(), 1);
    pages.push((page, 1));

    let Some(chrome) = chromium() else {
        assert!(
            !ci(),
            "no Chromium on the PATH (CI=true: a missing browser is a failure)"
        );
        eprintln!("skipped: the pages were not opened in a browser (no chromium on the PATH)");
        return;
    };
    for (i, (page, plots)) in pages.iter().enumerate() {
        let headings = browse(&chrome, page, &dir.join(format!("browser-{i}")), *plots);
        if i < 4 {
            assert_verdicts_lead(&page.display().to_string(), &headings, i == 3);
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn compare_refuses_what_is_not_a_summary_naming_the_file() {
    let dir = tmp_dir("cli-html-refuse");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{\"results\": []}").unwrap();
    let good = root().join("results/baselines/ci-guard.json");
    let o = crate::common::calbench(&[
        "compare",
        path_arg(&good),
        path_arg(&bad),
        "--out",
        path_arg(&dir.join("out")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("bad.json") && err.contains("scenario"),
        "{err}"
    );
    let o = crate::common::calbench(&[
        "compare",
        path_arg(&good),
        path_arg(&dir),
        "--out",
        path_arg(&dir.join("out")),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("summary.json"), "{err}");
    assert!(!dir.join("out").exists(), "nothing written");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_readme_shows_a_committed_screenshot_of_the_default_study_page() {
    let readme = read(&root().join("README.md"));
    let image = "assets/report-default.png";
    assert!(
        readme.contains(&format!("]({image})")),
        "README.md shows {image}"
    );
    let bytes = std::fs::read(root().join(image)).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"), "{image} is a PNG");
}
