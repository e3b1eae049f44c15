//! Import mappings whose keys take a narrower set than they read (docs/formats.md, import
//! mappings): a position's unit is a length's, an orientation's an angle's; an Euler sequence
//! is in lower case (`frame` says intrinsic or extrinsic); a separator is no part of a number.
//! Each is refused naming the mapping file, the line and the key, and nothing is written.

use std::path::Path;

use crate::common::{read, tmp_dir, ur10_example};
use crate::interchange::refused_mapping;

#[test]
fn a_mapping_key_out_of_its_own_set_is_refused_naming_what_it_takes() {
    let d = tmp_dir("mapping-sets");
    let mapping = read(Path::new(&ur10_example("mapping.toml")));
    let cases = [
        // A position's unit is a length's: the refusal lists the lengths alone, where it
        // listed the angles too and then refused them.
        (
            "unit = \"mm\"\n",
            "unit = \"cm\"\n",
            14,
            "unknown variant `cm`, expected `mm` or `m`",
        ),
        (
            "unit = \"mm\"\n",
            "unit = \"deg\"\n",
            14,
            "unknown variant `deg`, expected `mm` or `m`",
        ),
        (
            "\nunit = \"deg\"",
            "\nunit = \"mm\"",
            21,
            "unknown variant `mm`, expected `deg` or `rad`",
        ),
        // A separator that is part of a number would split numbers apart.
        (
            "separator = \";\"",
            "separator = \"-\"",
            3,
            "\"-\": an ASCII character other than the quote, a line break, a letter",
        ),
        // Upper case reads as intrinsic in some libraries, against `frame`.
        (
            "sequence = \"xyz\"",
            "sequence = \"XYZ\"",
            19,
            "three of x, y, z in lower case",
        ),
    ];
    for (i, (from, to, line, expected)) in cases.iter().enumerate() {
        let msg = refused_mapping(&d, &mapping, i, (from, to));
        assert!(msg.contains(&format!("m{i}.toml: line {line}")), "{msg}");
        assert!(msg.contains(expected), "{msg}");
    }
}
