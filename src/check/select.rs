//! Which scenes of a suite a run takes: `--filter PATTERN` and `--shard K/N`.
//!
//! Both look at a scene's *name*, its path relative to the suite folder without `.ron`, with
//! `/` between folders (`matlab-shiny`, `lights/spot`): the same on every machine and in every
//! checkout, whatever folder the suite was named by on the command line.
//!
//! - A filter pattern without `*` or `?` matches when the name, or the scene's path as
//!   printed (`scenes/matlab-shiny.ron`), contains it. With them it is a glob that must match
//!   the whole name or the whole printed path: `?` is one character, `*` any run of characters
//!   but `/`, `**` any run including `/`. Several patterns: a scene matching any is taken.
//! - A shard is picked by hashing the name with 64-bit FNV-1a, a fixed function (std's hasher
//!   is seeded per process, so shards would change between runs), then mixing the hash with
//!   MurmurHash3's 64-bit finalizer and mapping it onto `0..N` with a multiply-and-shift. The
//!   mixing matters: FNV-1a's last step barely reaches the high bits, so names that differ in
//!   their last character (`scene-1`, `scene-2`) would mostly share a shard, and its lowest bit
//!   is only the parity of the bytes' lowest bits, so `% 2` would split badly too. Every name
//!   lands in exactly one of the N shards, so N CI jobs cover a suite exactly once.
//!
//! Rejected: sharding by position in the sorted list (adding one scene would move most of
//! the others to another shard, and shards would change when one job sees a different file
//! set); the `globset` crate (three wildcards need a dozen lines, not a dependency).

use std::str::FromStr;

/// The `--filter` patterns of a run; empty takes every scene.
#[derive(Debug, Clone, Default)]
pub struct NameFilter {
    patterns: Vec<String>,
}

impl NameFilter {
    pub fn new(patterns: &[String]) -> Self {
        NameFilter {
            patterns: patterns.to_vec(),
        }
    }

    /// Whether the scene called `name`, printed as `path`, is taken.
    pub fn matches(&self, name: &str, path: &str) -> bool {
        self.patterns.is_empty()
            || self
                .patterns
                .iter()
                .any(|pattern| pattern_matches(pattern, name) || pattern_matches(pattern, path))
    }
}

/// A substring test, or a glob test when `pattern` has a wildcard.
fn pattern_matches(pattern: &str, text: &str) -> bool {
    if pattern.contains(['*', '?']) {
        glob_matches(pattern, text)
    } else {
        text.contains(pattern)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum GlobToken {
    Literal(char),
    /// `?`
    AnyChar,
    /// `*`
    AnyWithinFolder,
    /// `**`
    AnyAcrossFolders,
}

fn glob_tokens(pattern: &str) -> Vec<GlobToken> {
    let mut tokens = Vec::new();
    let mut chars = pattern.chars().peekable();
    while let Some(c) = chars.next() {
        tokens.push(match c {
            '?' => GlobToken::AnyChar,
            '*' if chars.peek() == Some(&'*') => {
                chars.next();
                GlobToken::AnyAcrossFolders
            }
            '*' => GlobToken::AnyWithinFolder,
            c => GlobToken::Literal(c),
        });
    }
    tokens
}

/// Whether the whole of `text` matches `pattern`: dynamic programming over (token, char), so
/// no pattern can take exponential time.
fn glob_matches(pattern: &str, text: &str) -> bool {
    let tokens = glob_tokens(pattern);
    let text: Vec<char> = text.chars().collect();
    // `matched[j]`: the tokens so far match `text[..j]`.
    let mut matched = vec![false; text.len() + 1];
    matched[0] = true;
    for token in tokens {
        let mut next = vec![false; text.len() + 1];
        for j in 0..=text.len() {
            next[j] = match token {
                GlobToken::Literal(c) => j > 0 && matched[j - 1] && text[j - 1] == c,
                GlobToken::AnyChar => j > 0 && matched[j - 1] && text[j - 1] != '/',
                // Zero characters, or one more (not `/`) after a shorter match.
                GlobToken::AnyWithinFolder => matched[j] || (j > 0 && next[j - 1] && text[j - 1] != '/'),
                GlobToken::AnyAcrossFolders => matched[j] || (j > 0 && next[j - 1]),
            };
        }
        matched = next;
    }
    matched[text.len()]
}

/// `--shard K/N`: the K-th of N disjoint parts of a suite (K from 1 to N).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based.
    pub index: u32,
    pub count: u32,
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let usage = || format!("`{text}` is not a shard: write K/N with 1 ≤ K ≤ N, e.g. 2/4");
        let (index, count) = text.split_once('/').ok_or_else(usage)?;
        let index: u32 = index.trim().parse().map_err(|_| usage())?;
        let count: u32 = count.trim().parse().map_err(|_| usage())?;
        if count == 0 || index == 0 || index > count {
            return Err(usage());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Whether the scene called `name` belongs to this shard.
    pub fn contains(&self, name: &str) -> bool {
        shard_of(name, self.count) == self.index
    }
}

/// The shard (1 to `count`) that the scene called `name` belongs to.
pub fn shard_of(name: &str, count: u32) -> u32 {
    let hash = mix_bits(fnv1a_64(name.as_bytes()));
    let scaled = (u128::from(hash) * u128::from(count)) >> 64;
    // `scaled < count`, so it fits in u32.
    scaled as u32 + 1
}

/// MurmurHash3's `fmix64`: every input bit affects every output bit.
fn mix_bits(mut hash: u64) -> u64 {
    hash ^= hash >> 33;
    hash = hash.wrapping_mul(0xff51_afd7_ed55_8ccd);
    hash ^= hash >> 33;
    hash = hash.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    hash ^ (hash >> 33)
}

/// 64-bit FNV-1a.
pub fn fnv1a_64(bytes: &[u8]) -> u64 {
    const OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    bytes.iter().fold(OFFSET_BASIS, |hash, &byte| {
        (hash ^ u64::from(byte)).wrapping_mul(PRIME)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_the_reference_vectors() {
        assert_eq!(fnv1a_64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a_64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a_64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn shards_are_stable_and_cover_every_name_once() {
        // Fixed values: a change here would reshuffle every team's CI matrix.
        let fixed: Vec<u32> = ["matlab-shiny", "minimal", "lights/spot"]
            .iter()
            .map(|name| shard_of(name, 4))
            .collect();
        assert_eq!(fixed, [1, 4, 4]);
        let names: Vec<String> = (0..1000).map(|i| format!("suite/scene-{i:04}")).collect();
        for count in [1, 2, 3, 7] {
            let mut sizes = vec![0usize; count as usize];
            for name in &names {
                let owners: Vec<u32> = (1..=count)
                    .filter(|&index| Shard { index, count }.contains(name))
                    .collect();
                assert_eq!(owners.len(), 1, "{name} in shards {owners:?} of {count}");
                sizes[owners[0] as usize - 1] += 1;
            }
            // Roughly balanced: no shard gets less than half its fair share.
            let fair = names.len() / count as usize;
            assert!(sizes.iter().all(|&size| size * 2 > fair), "{count}: {sizes:?}");
        }
    }

    #[test]
    fn shard_syntax() {
        assert_eq!("2/4".parse(), Ok(Shard { index: 2, count: 4 }));
        assert_eq!("1/1".parse(), Ok(Shard { index: 1, count: 1 }));
        for bad in ["0/4", "5/4", "1/0", "2", "a/b", "-1/3", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        assert_eq!(Shard { index: 3, count: 8 }.to_string(), "3/8");
    }

    #[test]
    fn globs() {
        let cases = [
            ("matlab-*", "matlab-shiny", true),
            ("matlab-*", "lights/matlab-shiny", false),
            ("*/spot", "lights/spot", true),
            ("*", "lights/spot", false),
            ("**", "lights/spot", true),
            ("**spot", "a/b/spot", true),
            ("lights/**", "lights/a/b", true),
            ("light-?????", "light-point", true),
            ("light-?????", "light-spot", false),
            ("?", "/", false),
            ("a*b*c", "abxbxc", true),
            ("a*b*c", "abxbx", false),
            ("", "", true),
            ("*", "", true),
        ];
        for (pattern, text, expected) in cases {
            assert_eq!(glob_matches(pattern, text), expected, "{pattern} on {text}");
        }
    }

    #[test]
    fn filters_match_names_or_printed_paths() {
        let filter = NameFilter::new(&["shiny".to_owned(), "scenes/light-*.ron".to_owned()]);
        assert!(filter.matches("matlab-shiny", "scenes/matlab-shiny.ron"));
        assert!(filter.matches("light-spot", "scenes/light-spot.ron"));
        assert!(!filter.matches("matlab-metal", "scenes/matlab-metal.ron"));
        assert!(
            NameFilter::new(&["scenes/matlab".to_owned()]).matches("matlab-metal", "scenes/matlab-metal.ron")
        );
        assert!(NameFilter::default().matches("anything", "anything.ron"));
    }
}
