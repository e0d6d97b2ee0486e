//! Fixed-length arrays of a scene, read exactly. The toml crate fills a
//! `[f64; 2]` from the first entries of a longer array and drops the rest
//! without a word (`mesh.divisions = [4, 3, 2]` gave a 4 × 3 mesh, `point =
//! [1, 2, 3, 4]` the point (1, 2, 3)); these read a list and check its
//! length, so that the loader names the key (`... expected an array of 2
//! entries`).

use serde::de::Error;
use serde::{Deserialize, Deserializer};

/// `[T; N]`, from a list of exactly N entries.
pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v = Vec::<T>::deserialize(d)?;
    let len = v.len();
    v.try_into()
        .map_err(|_| D::Error::invalid_length(len, &format!("an array of {N} entries").as_str()))
}

/// [`array`] of an optional key (with `#[serde(default)]`).
pub fn option<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    array(d).map(Some)
}

/// `[[T; M]; N]`, every level exactly.
pub fn nested<'de, D, T, const M: usize, const N: usize>(d: D) -> Result<[[T; M]; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    let rows = Vec::<Vec<T>>::deserialize(d)?;
    let len = rows.len();
    let mut out = Vec::with_capacity(N);
    for row in rows {
        let n = row.len();
        out.push(
            row.try_into().map_err(|_| {
                D::Error::invalid_length(n, &format!("rows of {M} entries").as_str())
            })?,
        );
    }
    out.try_into()
        .map_err(|_| D::Error::invalid_length(len, &format!("an array of {N} rows").as_str()))
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    #[derive(Deserialize, Debug)]
    struct Raw {
        #[serde(default, deserialize_with = "super::option")]
        pair: Option<[usize; 2]>,
        #[serde(default, deserialize_with = "super::option")]
        point: Option<[f64; 3]>,
        #[serde(default, deserialize_with = "super::nested")]
        bounds: [[f64; 3]; 2],
    }

    fn read(text: &str) -> Result<Raw, String> {
        toml::from_str::<Raw>(text).map_err(|e| e.to_string())
    }

    #[test]
    fn arrays_of_the_wrong_length_are_refused() {
        let ok =
            read("pair = [4, 3]\npoint = [1, 2, 3.5]\nbounds = [[0, 0, 0], [1, 1, 1]]").unwrap();
        assert_eq!(ok.pair, Some([4, 3]));
        assert_eq!(ok.point, Some([1.0, 2.0, 3.5]));
        assert_eq!(ok.bounds[1], [1.0; 3]);
        let absent = read("").unwrap();
        assert!(absent.pair.is_none() && absent.point.is_none());
        for (text, want) in [
            ("pair = [4, 3, 2]", "an array of 2 entries"),
            ("pair = [4]", "an array of 2 entries"),
            ("point = [1, 2, 3, 4]", "an array of 3 entries"),
            (
                "bounds = [[0, 0, 0], [1, 1, 1], [2, 2, 2]]",
                "an array of 2 rows",
            ),
            ("bounds = [[0, 0], [1, 1, 1]]", "rows of 3 entries"),
            ("pair = [4, \"a\"]", "expected usize"),
        ] {
            let e = read(text).unwrap_err();
            assert!(e.contains(want), "{text}: {e}");
        }
    }
}
