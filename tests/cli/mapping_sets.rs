//! Import mappings refused at the line of their key (docs/formats.md, import mappings): TOML
//! that is no mapping (a key twice, a wrong type or length, an unknown key), and keys out of
//! the narrower set they take (a position's unit is a length's, an orientation's an angle's;
//! an Euler sequence is in lower case, `frame` saying intrinsic or extrinsic; a separator is
//! no part of a number). Nothing is written.

use std::path::Path;

use crate::common::{read, tmp_dir, ur10_example};
use crate::interchange::refused_mapping;

#[test]
fn a_mapping_key_out_of_its_own_set_is_refused_naming_what_it_takes() {
    refused_at_lines(
        "mapping-sets",
        &[
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
            // A `;` export read with `,`: its header is one column, which had been listed
            // as the whole header without a word on the separator.
            (
                "separator = \";\"\ndecimal = \",\"",
                "separator = \",\"\ndecimal = \".\"",
                7,
                "the header reads as one column, and holds ';': is the mapping's `separator` the \
                 export's?",
            ),
            // Upper case reads as intrinsic in some libraries, against `frame`.
            (
                "sequence = \"xyz\"",
                "sequence = \"XYZ\"",
                19,
                "three of x, y, z in lower case",
            ),
        ],
    );
}

/// A mapping that is not valid TOML for a mapping (a key given twice, a value of the wrong
/// type, an array of the wrong length, an unknown key) is refused naming the mapping file and
/// the line, as a robot or scenario file is.
#[test]
fn import_refuses_a_malformed_mapping_naming_its_line() {
    refused_at_lines(
        "interchange-mapping-toml",
        &[
            (
                "unit = \"mm\"\n",
                "unit = \"mm\"\nunit = \"m\"\n",
                15,
                "duplicate key",
            ),
            ("unit = \"rad\"", "unit = 1", 9, ""),
            (
                "columns = [\"measurement_x\", \"measurement_y\", \"measurement_z\"]",
                "columns = [\"measurement_x\", \"measurement_y\"]",
                13,
                "expected an array of length 3",
            ),
            (
                "sequence = \"xyz\"",
                "sequenc = \"xyz\"",
                19,
                "unknown field `sequenc`",
            ),
        ],
    );
}

/// Each of `cases` (`from`, `to`, line, words), the UR10 example's mapping with `from` replaced
/// by `to` ([`refused_mapping`], in a fresh folder `name`): refused naming the mapping file at
/// that line, with those words.
pub(crate) fn refused_at_lines(name: &str, cases: &[(&str, &str, usize, &str)]) {
    let d = tmp_dir(name);
    let mapping = read(Path::new(&ur10_example("mapping.toml")));
    for (i, (from, to, line, expected)) in cases.iter().enumerate() {
        let msg = refused_mapping(&d, &mapping, i, (from, to));
        assert!(msg.contains(&format!("m{i}.toml: line {line}")), "{msg}");
        assert!(msg.contains(expected), "{msg}");
    }
}
