//! Point ids as signac computes its job ids.
//!
//! signac (`signac.job.calc_id`) encodes a state point with Python's
//! `json.dumps(statepoint, sort_keys=True)` and takes the MD5 of the UTF-8 bytes, as 32
//! lower-case hexadecimal digits. With Python's defaults that JSON text has:
//!
//! * keys sorted (by code point) at every level;
//! * the separators `", "` between items and `": "` between a key and its value;
//! * floats written as Python's `repr`: the shortest digits that read back to the same
//!   `f64`, in plain notation with at least one decimal (`1.0`, `0.0001`,
//!   `1000000000000000.0`) when the decimal exponent is in `[-4, 16)`, and in scientific
//!   notation with a signed exponent of at least two digits (`1e-05`, `2.5e+16`)
//!   otherwise;
//! * integers in decimal, `true`, `false`;
//! * strings ASCII only (`ensure_ascii`): `\"`, `\\`, `\n`, `\r`, `\t`, `\b`, `\f`, other
//!   characters below U+0020 and every character above U+007F as `\uXXXX` (lower-case
//!   hex, UTF-16 surrogate pairs above U+FFFF).
//!
//! [`canonical_json`] writes exactly that text and [`md5_hex`] digests it (RFC 1321), so
//! [`point_id`] of a state point is the id signac gives the same state point: a signac
//! project opened on a sweep's folder finds every point under its own id.

use std::fmt::Write;

use serde_json::Value;

/// The id of a point: the MD5 of its state point's canonical JSON ([`canonical_json`]).
pub fn point_id(statepoint: &Value) -> String {
    md5_hex(canonical_json(statepoint).as_bytes())
}

/// `json.dumps(value, sort_keys=True)` as CPython writes it.
pub fn canonical_json(value: &Value) -> String {
    let mut out = String::new();
    write(&mut out, value);
    out
}

fn write(out: &mut String, value: &Value) {
    match value {
        Value::Null => out.push_str("null"),
        Value::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
        Value::Number(n) => match (n.as_i64(), n.as_u64(), n.as_f64()) {
            (Some(i), _, _) if !n.is_f64() => {
                let _ = write!(out, "{i}");
            }
            (_, Some(u), _) if !n.is_f64() => {
                let _ = write!(out, "{u}");
            }
            (_, _, Some(x)) => push_python_float(out, x),
            _ => out.push_str("null"),
        },
        Value::String(s) => string(out, s),
        Value::Array(items) => {
            out.push('[');
            for (k, v) in items.iter().enumerate() {
                if k > 0 {
                    out.push_str(", ");
                }
                write(out, v);
            }
            out.push(']');
        }
        Value::Object(map) => {
            let mut keys: Vec<&String> = map.keys().collect();
            keys.sort();
            out.push('{');
            for (k, key) in keys.into_iter().enumerate() {
                if k > 0 {
                    out.push_str(", ");
                }
                string(out, key);
                out.push_str(": ");
                write(out, &map[key]);
            }
            out.push('}');
        }
    }
}

fn string(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            ' '..='\u{7f}' => out.push(c),
            _ => {
                let mut units = [0u16; 2];
                for u in c.encode_utf16(&mut units) {
                    let _ = write!(out, "\\u{u:04x}");
                }
            }
        }
    }
    out.push('"');
}

/// Python's `repr` of a finite float (`NaN`, `Infinity`, `-Infinity` otherwise).
pub fn python_float(x: f64) -> String {
    let mut out = String::new();
    push_python_float(&mut out, x);
    out
}

/// [`python_float`] appended to `out` (no allocation of its own: an expansion writes
/// a float or more per point).
pub fn push_python_float(out: &mut String, x: f64) {
    if x.is_nan() {
        return out.push_str("NaN");
    }
    if x.is_infinite() {
        return out.push_str(if x > 0.0 { "Infinity" } else { "-Infinity" });
    }
    // Rust's `{:e}` writes the shortest round-trip digits: `-d.ddde-N`.
    let mut sci = Stack::default();
    let _ = write!(sci, "{x:e}");
    let sci = sci.as_str();
    let (mantissa, exp) = sci.split_once('e').unwrap_or((sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    if !(-4..16).contains(&exp) {
        let sign = if exp < 0 { '-' } else { '+' };
        let _ = write!(out, "{mantissa}e{sign}{:02}", exp.abs());
        return;
    }
    // Plain notation with the same digits: the point moved `exp` places.
    let (negative, mantissa) = match mantissa.strip_prefix('-') {
        Some(m) => (true, m),
        None => (false, mantissa),
    };
    let digits = || mantissa.bytes().filter(u8::is_ascii_digit).map(char::from);
    if negative {
        out.push('-');
    }
    if exp < 0 {
        out.push_str("0.");
        out.extend(std::iter::repeat_n('0', (-exp - 1) as usize));
        out.extend(digits());
    } else {
        let whole = exp as usize + 1;
        let n = digits().count();
        out.extend(digits().take(whole));
        out.extend(std::iter::repeat_n('0', whole.saturating_sub(n)));
        out.push('.');
        if n > whole {
            out.extend(digits().skip(whole));
        } else {
            out.push('0');
        }
    }
}

/// A short text on the stack (a float's `{:e}` is at most 24 bytes).
#[derive(Default)]
struct Stack {
    bytes: [u8; 32],
    len: usize,
}

impl Stack {
    fn as_str(&self) -> &str {
        std::str::from_utf8(&self.bytes[..self.len]).unwrap_or("")
    }
}

impl std::fmt::Write for Stack {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        let end = self.len + s.len();
        self.bytes
            .get_mut(self.len..end)
            .ok_or(std::fmt::Error)?
            .copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// MD5 (RFC 1321) of `data`, as 32 lower-case hexadecimal digits.
pub fn md5_hex(data: &[u8]) -> String {
    // K[i] = floor(2^32 |sin(i + 1)|), computed once (an expansion takes an id per
    // point).
    static K: std::sync::OnceLock<[u32; 64]> = std::sync::OnceLock::new();
    let k = K.get_or_init(|| {
        std::array::from_fn(|i| ((i as f64 + 1.0).sin().abs() * 4_294_967_296.0) as u32)
    });
    let mut h: [u32; 4] = [0x6745_2301, 0xefcd_ab89, 0x98ba_dcfe, 0x1032_5476];
    // The whole blocks of the message, then its tail padded (0x80, zeros, the length
    // in bits) in one or two more blocks on the stack: no copy of the message.
    let whole = data.len() / 64 * 64;
    for block in data[..whole].chunks_exact(64) {
        md5_block(&mut h, block, k);
    }
    let rest = &data[whole..];
    let mut tail = [0u8; 128];
    tail[..rest.len()].copy_from_slice(rest);
    tail[rest.len()] = 0x80;
    let end = if rest.len() < 56 { 64 } else { 128 };
    tail[end - 8..end].copy_from_slice(&((data.len() as u64).wrapping_mul(8)).to_le_bytes());
    for block in tail[..end].chunks_exact(64) {
        md5_block(&mut h, block, k);
    }
    const HEX: &[u8; 16] = b"0123456789abcdef";
    let mut out = String::with_capacity(32);
    for byte in h.iter().flat_map(|w| w.to_le_bytes()) {
        out.push(HEX[usize::from(byte >> 4)] as char);
        out.push(HEX[usize::from(byte & 15)] as char);
    }
    out
}

/// One 64-byte block of MD5 into the state `h`.
fn md5_block(h: &mut [u32; 4], block: &[u8], k: &[u32; 64]) {
    const S: [u32; 16] = [7, 12, 17, 22, 5, 9, 14, 20, 4, 11, 16, 23, 6, 10, 15, 21];
    let m: [u32; 16] = std::array::from_fn(|i| {
        u32::from_le_bytes([
            block[4 * i],
            block[4 * i + 1],
            block[4 * i + 2],
            block[4 * i + 3],
        ])
    });
    let [mut a, mut b, mut c, mut d] = *h;
    for i in 0..64 {
        let (f, g) = match i / 16 {
            0 => ((b & c) | (!b & d), i),
            1 => ((d & b) | (!d & c), (5 * i + 1) % 16),
            2 => (b ^ c ^ d, (3 * i + 5) % 16),
            _ => (c ^ (b | !d), (7 * i) % 16),
        };
        let rotated = a
            .wrapping_add(f)
            .wrapping_add(k[i])
            .wrapping_add(m[g])
            .rotate_left(S[(i / 16) * 4 + i % 4]);
        (a, d, c) = (d, c, b);
        b = b.wrapping_add(rotated);
    }
    for (x, y) in h.iter_mut().zip([a, b, c, d]) {
        *x = x.wrapping_add(y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn md5_of_the_rfc_1321_test_suite() {
        // RFC 1321, appendix A.5.
        for (text, digest) in [
            ("", "d41d8cd98f00b204e9800998ecf8427e"),
            ("a", "0cc175b9c0f1b6a831c399e269772661"),
            ("abc", "900150983cd24fb0d6963f7d28e17f72"),
            ("message digest", "f96b697d7cb7938d525a2f31aaf161d0"),
            (
                "abcdefghijklmnopqrstuvwxyz",
                "c3fcd3d76192e4007dfb496cca67e13b",
            ),
            (
                "12345678901234567890123456789012345678901234567890123456789012345678901234567890",
                "57edf4a22be3c955ac49da2e2107b67a",
            ),
        ] {
            assert_eq!(md5_hex(text.as_bytes()), digest, "{text:?}");
        }
    }

    /// Python's float repr as first written here: `{:e}` for the exponent, Rust's
    /// `Display` (the same shortest digits, in plain notation) inside `[-4, 16)`.
    fn reference_repr(x: f64) -> String {
        let sci = format!("{x:e}");
        let (mantissa, exp) = sci.split_once('e').unwrap();
        let exp: i32 = exp.parse().unwrap();
        if (-4..16).contains(&exp) {
            let plain = format!("{x}");
            if plain.contains('.') {
                plain
            } else {
                plain + ".0"
            }
        } else {
            let sign = if exp < 0 { '-' } else { '+' };
            format!("{mantissa}e{sign}{:02}", exp.abs())
        }
    }

    #[test]
    fn the_float_repr_moves_the_point_as_display_does() {
        let mut cases = vec![0.0, -0.0, 1.0, 1e15, 9.999e15, 1e16, 1e-4, 9.99e-5, 123.456];
        // Floats of every exponent in and around the plain range, many digit counts.
        let mut bits: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..20_000 {
            bits ^= bits << 13;
            bits ^= bits >> 7;
            bits ^= bits << 17;
            let mantissa = (bits >> 11) as f64 / (1u64 << 53) as f64;
            let exp = (bits % 48) as i32 - 12;
            let digits = (bits >> 7) % 17 + 1;
            let scale = 10f64.powi(digits as i32);
            let rounded = (mantissa * scale).round() / scale;
            for x in [mantissa, rounded] {
                let x = x * 10f64.powi(exp);
                cases.push(if bits & 1 == 0 { x } else { -x });
            }
        }
        for x in cases {
            assert_eq!(python_float(x), reference_repr(x), "{x:e}");
        }
    }

    #[test]
    fn ids_are_the_ids_signac_gives() {
        // signac's documentation: project.open_job({'a': 0}).id.
        assert_eq!(
            point_id(&json!({"a": 0})),
            "9bfd29df07674bc4aa960cf661b5acd2"
        );
        // The rest printed by CPython 3.11: json.dumps(sp, sort_keys=True) and
        // hashlib.md5 of it (signac.job.calc_id).
        let helix = json!({"helix": {"head_ratio": 1.2599210498948732, "dhat": 1.05}});
        assert_eq!(
            canonical_json(&helix),
            r#"{"helix": {"dhat": 1.05, "head_ratio": 1.2599210498948732}}"#
        );
        assert_eq!(point_id(&helix), "17f88ae8b3c20139a29cfdc950a1b23c");
        let mixed = json!({"integrator": {"method": "overdamped2", "dt": 0.1},
                           "brownian": {"temperature": 1e-5, "seed": 3}});
        assert_eq!(point_id(&mixed), "450477d974ff7296da697d15729e3d27");
        let odd = json!({"x": [1e16, 1e15, 0.0001, -0.0, 2.5e-7, 123456789012345678.0, true,
                               "\u{e9}\n\"\u{1f600}"]});
        assert_eq!(
            canonical_json(&odd),
            r#"{"x": [1e+16, 1000000000000000.0, 0.0001, -0.0, 2.5e-07, 1.2345678901234568e+17, true, "\u00e9\n\"\ud83d\ude00"]}"#
        );
        assert_eq!(point_id(&odd), "be570f562b1893797823bcbf7ecd3af7");
    }
}
