//! Counts in words, as every message and report prints them: "1 lenslet", "2 lenslets",
//! "0 triangles", never "lenslet(s)" or "1 lenslets". English plurals of the nouns inimtrace
//! counts: `-s`, `-es` after s, x, z, ch and sh (`mesh` -> `meshes`), `-ies` after a consonant
//! and y (`entry` -> `entries`); an irregular noun gives its plural ([`count_as`]).

use std::fmt::Display;

/// `n` and `noun`, the noun in the plural unless `n` is one: `count(1, "point")` is
/// `"1 point"`, `count(3, "point")` is `"3 points"`, `count(0, "point")` is `"0 points"`.
pub fn count<N: Display + PartialEq + From<u8>>(n: N, noun: &str) -> String {
    count_as(n, noun, &plural(noun))
}

/// [`count`] with the plural given: `count_as(2, "vertex", "vertices")`.
pub fn count_as<N: Display + PartialEq + From<u8>>(n: N, singular: &str, plural: &str) -> String {
    let one = n == N::from(1u8);
    format!("{n} {}", if one { singular } else { plural })
}

/// The regular English plural of `noun` (its last word: `score row` -> `score rows`).
pub fn plural(noun: &str) -> String {
    let consonant_y = noun.ends_with('y')
        && noun.len() > 1
        && !noun[..noun.len() - 1].ends_with(|c: char| "aeiou".contains(c.to_ascii_lowercase()));
    if consonant_y {
        format!("{}ies", &noun[..noun.len() - 1])
    } else if ["s", "x", "z", "ch", "sh"].iter().any(|e| noun.ends_with(e)) {
        format!("{noun}es")
    } else {
        format!("{noun}s")
    }
}
