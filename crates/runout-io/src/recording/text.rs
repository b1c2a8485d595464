//! Low-level text handling: line classification, field splitting and a fast exact float parser.
//!
//! The float parser is specialised for recording cells (`-12.345`, `1,5` with decimal commas,
//! `3.2e-05`): it accumulates up to 19 significant digits in a `u64` and, when the mantissa is
//! below 2⁵³ and the power of ten at most 10²², returns `m·10^e` or `m/10^−e`, which is
//! correctly rounded because both operands are exact (Clinger's fast path). Anything else falls
//! back to `str::parse::<f64>` (also correctly rounded). It is ~3–4× faster than going through
//! the `csv` crate's records + `str::parse` (figure in `benches/read.rs` and the module docs).
//! On x86-64 with SSSE3 and SSE4.1 the parse workers take rows of plain cells through
//! [`WideCells`] first (a structural index of the text, then each cell from its known bounds),
//! with the same bits as the scalar path.

/// Exact powers of ten representable in f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Trim ASCII blanks and one pair of surrounding double quotes.
#[inline]
pub(crate) fn trim_field(mut b: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = b {
        if *first == b' ' || *first == b'\t' {
            b = rest;
        } else {
            break;
        }
    }
    while let [rest @ .., last] = b {
        if *last == b' ' || *last == b'\t' || *last == b'\r' {
            b = rest;
        } else {
            break;
        }
    }
    if b.len() >= 2 && b[0] == b'"' && b[b.len() - 1] == b'"' {
        b = &b[1..b.len() - 1];
    }
    b
}

/// Parse one cell as a finite f64; `decimal_comma` accepts `,` as the decimal separator.
/// Returns `None` for anything that is not a finite number (empty, text, `nan`, `inf`).
///
/// Two tight digit loops (integer and fraction part) accumulate the mantissa; the digit counts
/// come from positions, not per-digit counters (issue 18: ≈ 1.6× the per-digit state machine
/// it replaced). With at most 19 digits the mantissa is exact in a `u64`; Clinger's fast path
/// then applies as described in the module docs, anything else goes to [`slow_parse`].
///
/// The common cell (digits, an optional fraction, no exponent, at most 19 digits, a mantissa
/// below 2⁵³) is parsed inline ([`Mantissa::fast_value`]); anything else goes on from the same
/// scan in [`number_from`] (issue 18: the fast path inlined into the row loop, the digits
/// scanned once for every cell).
#[inline(always)]
pub(crate) fn parse_number(cell: &[u8], decimal_comma: bool) -> Option<f64> {
    let b = trim_field(cell);
    let m = scan_mantissa(b, decimal_comma);
    match m.fast_value() {
        Some(v) if m.end == b.len() => Some(v),
        _ => number_from(b, m, decimal_comma),
    }
}

/// A number cell at the start of `rest` (a row from a cell's first byte on) that ends at the
/// delimiter `delim` or at the end of `rest`, parsed in the same pass that finds its end: the
/// value and the cell's length. The digits are scanned once: a common cell (sign, digits,
/// fraction) ends at the delimiter and is done; one with an exponent goes on from where the scan
/// stopped ([`number_from`]). `None` when the cell is not a clean number (leading or trailing
/// blanks, quotes, text, an invalid form): the caller then splits the cell off and parses it
/// with [`parse_number`], which gives the same value for every cell accepted here (issue 18: one
/// pass over the bytes instead of a delimiter search followed by the digit scan).
///
/// The caller must not use it when `delim` can be part of a number (a digit, a sign, `.`, or
/// `,` with decimal commas): see [`delimiter_ends_numbers`].
#[inline(always)]
pub(crate) fn parse_leading_number(
    rest: &[u8],
    delim: u8,
    decimal_comma: bool,
) -> Option<(f64, usize)> {
    let m = scan_mantissa(rest, decimal_comma);
    let stop = m.end;
    if stop == rest.len() || rest[stop] == delim {
        return m.fast_value().map(|v| (v, stop));
    }
    leading_number_from(rest, delim, decimal_comma, m)
}

/// A common number cell (sign, digits, fraction: no exponent, no blanks) at the start of
/// `rest`, ended by `delim`, a line feed or a carriage return: its value, its length and the byte
/// that ended it. `None` for anything else, and when nothing follows the cell in `rest`. For a
/// cell it accepts, the value is that of [`parse_leading_number`] on the cell (the same digit
/// scan and fast path), used where a row's cells are parsed without first finding the row's end
/// (issue 18).
#[inline(always)]
pub(crate) fn parse_common_cell(
    rest: &[u8],
    delim: u8,
    decimal_comma: bool,
) -> Option<(f64, usize, u8)> {
    let m = scan_mantissa(rest, decimal_comma);
    let stop = m.end;
    let end = *rest.get(stop)?;
    if end == delim || end == b'\n' || end == b'\r' {
        return m.fast_value().map(|v| (v, stop, end));
    }
    None
}

/// Recording rows parsed sixteen and sixty-four bytes at a time (issue 18), on x86-64 with
/// SSSE3 and SSE4.1 ([`WideCells::detect`]): the positions of a stretch's delimiters and line
/// feeds ([`WideCells::structurals`]), then each number cell from its known bounds
/// ([`WideCells::number_cell`]), without a branch per digit and without one cell's parse
/// waiting for the previous cell's end.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideCells {
    /// Private: made only by [`WideCells::detect`], so holding one proves the CPU features.
    _proof: (),
}

#[cfg(target_arch = "x86_64")]
impl WideCells {
    /// The wide parser when this CPU can run it.
    pub(crate) fn detect() -> Option<Self> {
        (is_x86_feature_detected!("ssse3") && is_x86_feature_detected!("sse4.1"))
            .then_some(Self { _proof: () })
    }

    /// The positions of the bytes `delim` and `\n` in `bytes[from..to]`, counted from `from`,
    /// written to the start of `at` (which must hold `to − from + 64` positions: the spare room
    /// takes unconditional writes); returns how many. Sixty-four bytes per step: four compares
    /// give the step's bit mask, whose set bits are written eight at a time (a branch per
    /// eight positions, not per position, as in simdjson's structural index).
    #[target_feature(enable = "ssse3,sse4.1")]
    #[inline]
    pub(crate) fn structurals(
        self,
        bytes: &[u8],
        from: usize,
        to: usize,
        delim: u8,
        at: &mut [u32],
    ) -> usize {
        wide::structurals(&bytes[from..to], delim, at)
    }

    /// The number cell `bytes[a..a + len]` (a sign, digits, at most one decimal point — `.`, or
    /// `,` too with decimal commas — and at least one digit, at most 15 bytes), when 16 bytes
    /// from `a` are readable: `±mant / 10^frac_digits`, the same expression on the same
    /// integers as [`parse_common_cell`]'s fast path, so the same bits as [`parse_number`] of
    /// the cell. `None` for any other cell (the caller parses the row the scalar way).
    ///
    /// The cell's digit and point positions come from vector compares (bit masks), the digits
    /// are gathered right-aligned into one register (`pshufb`, with a mask looked up by the
    /// lengths of the integer and fraction runs) and combined by the multiply-add ladder of SIMD
    /// number parsing (10·a + b, 100·a + b, 10⁴·a + b, then 10⁸·a + b).
    #[target_feature(enable = "ssse3,sse4.1")]
    #[inline]
    pub(crate) fn number_cell(
        self,
        bytes: &[u8],
        a: usize,
        len: usize,
        decimal_comma: bool,
    ) -> Option<f64> {
        let window: &[u8; 16] = bytes.get(a..a.checked_add(16)?)?.try_into().ok()?;
        wide::number_cell(window, len, decimal_comma)
    }
}

#[cfg(target_arch = "x86_64")]
mod wide {
    use super::{with_sign, POW10};
    use std::arch::x86_64::*;

    /// Shuffle masks by the lengths of the integer run `a` and the fraction run `b` (`a + b ≤
    /// 15`): output byte `i` of 16 takes digit `k = i − (16 − a − b)` of the cell (counted from
    /// the first digit, skipping the decimal point after `a` digits), or zero (`0x80`) for
    /// `k < 0`. The sign's offset (0 or 1) is added at run time; `0x80 + 1` still selects zero.
    static GATHER: [[[u8; 16]; 16]; 16] = gather_masks();

    const fn gather_masks() -> [[[u8; 16]; 16]; 16] {
        let mut t = [[[0x80u8; 16]; 16]; 16];
        let mut a = 0;
        while a < 16 {
            let mut b = 0;
            while a + b < 16 {
                let n = a + b;
                let mut i = 16 - n;
                while i < 16 {
                    let k = i - (16 - n);
                    t[a][b][i] = if k < a { k as u8 } else { (k + 1) as u8 };
                    i += 1;
                }
                b += 1;
            }
            a += 1;
        }
        t
    }

    /// See [`super::WideCells::structurals`].
    #[target_feature(enable = "ssse3,sse4.1")]
    #[inline]
    pub(super) fn structurals(text: &[u8], delim: u8, at: &mut [u32]) -> usize {
        assert!(at.len() >= text.len() + 64, "room for the positions");
        let (d, nl) = (_mm_set1_epi8(delim as i8), _mm_set1_epi8(b'\n' as i8));
        let mut n = 0;
        let mut base = 0u32;
        let mut blocks = text.chunks_exact(64);
        for block in &mut blocks {
            let mut m = 0u64;
            for (q, part) in block.chunks_exact(16).enumerate() {
                // SAFETY: `part` has 16 bytes; unaligned load.
                let v = unsafe { _mm_loadu_si128(part.as_ptr().cast()) };
                let hit = _mm_or_si128(_mm_cmpeq_epi8(v, d), _mm_cmpeq_epi8(v, nl));
                m |= u64::from(_mm_movemask_epi8(hit) as u32) << (16 * q);
            }
            // at most `base` positions so far, so `n + 64 ≤ text.len() + 64`
            let out = &mut at[n..n + 64];
            let count = m.count_ones() as usize;
            let mut k = 0;
            while k < count {
                for slot in &mut out[k..k + 8] {
                    *slot = base + m.trailing_zeros();
                    m &= m.wrapping_sub(1);
                }
                k += 8;
            }
            n += count;
            base += 64;
        }
        for (k, &c) in blocks.remainder().iter().enumerate() {
            if c == delim || c == b'\n' {
                at[n] = base + k as u32;
                n += 1;
            }
        }
        n
    }

    /// See [`super::WideCells::number_cell`]; the cell is the first `len` bytes of `window`.
    #[target_feature(enable = "ssse3,sse4.1")]
    #[inline]
    pub(super) fn number_cell(window: &[u8; 16], len: usize, decimal_comma: bool) -> Option<f64> {
        if len == 0 || len > 15 {
            return None;
        }
        // SAFETY: 16 bytes; unaligned load.
        let v = unsafe { _mm_loadu_si128(window.as_ptr().cast()) };
        let d = _mm_sub_epi8(v, _mm_set1_epi8(b'0' as i8));
        // unsigned d ≤ 9 ⇔ min(d, 9) == d
        let digit = _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_min_epu8(d, _mm_set1_epi8(9)), d)) as u32;
        let mut point = _mm_cmpeq_epi8(v, _mm_set1_epi8(b'.' as i8));
        if decimal_comma {
            point = _mm_or_si128(point, _mm_cmpeq_epi8(v, _mm_set1_epi8(b',' as i8)));
        }
        let point = _mm_movemask_epi8(point) as u32;
        let first = window[0];
        let neg = first == b'-';
        let s = u32::from(neg || first == b'+');
        let len = len as u32;
        // the cell's bytes after the sign that are not digits: none, or one decimal point
        let other = ((1u32 << len) - 1) & !((1u32 << s) - 1) & !digit;
        if other & other.wrapping_sub(1) != 0 || other & !point != 0 {
            return None;
        }
        let has_point = other != 0;
        let p = if has_point {
            other.trailing_zeros()
        } else {
            len
        };
        let (a, b) = ((p - s) as usize, (len - p - u32::from(has_point)) as usize);
        if a + b == 0 {
            return None;
        }
        // SAFETY: a + b ≤ 15 (len ≤ 15), inside the table; 16-byte unaligned load of it.
        let mask = unsafe { _mm_loadu_si128(GATHER[a][b].as_ptr().cast()) };
        let digits = _mm_shuffle_epi8(d, _mm_add_epi8(mask, _mm_set1_epi8(s as i8)));
        let pairs = _mm_maddubs_epi16(digits, _mm_set1_epi16(0x010a)); // 10·d₀ + d₁
        let quads = _mm_madd_epi16(pairs, _mm_set1_epi32(0x0001_0064)); // 100·p₀ + p₁
        let quads16 = _mm_packus_epi32(quads, quads);
        let octs = _mm_madd_epi16(quads16, _mm_set1_epi32(0x0001_2710)); // 10⁴·q₀ + q₁
        let hi = _mm_cvtsi128_si32(octs) as u32;
        let lo = _mm_extract_epi32(octs, 1) as u32;
        // below 10¹⁵ < 2⁵³: exact as i64 and as f64
        let mant = u64::from(hi) * 100_000_000 + u64::from(lo);
        Some(with_sign(mant as i64 as f64 / POW10[b], neg))
    }
}

/// [`parse_leading_number`] for a cell whose digits did not reach the delimiter (an exponent):
/// its end is searched from where the scan stopped, and the cell parsed on from there when it
/// is already trimmed (it starts with a digit, a sign or a point, so only its end can hold
/// blanks or a quote).
#[cold]
#[inline(never)]
fn leading_number_from(
    rest: &[u8],
    delim: u8,
    decimal_comma: bool,
    m: Mantissa,
) -> Option<(f64, usize)> {
    if m.int_digits + m.frac_digits == 0 {
        return None;
    }
    let end = rest[m.end..]
        .iter()
        .position(|&c| c == delim)
        .map_or(rest.len(), |k| m.end + k);
    let cell = &rest[..end];
    if matches!(cell.last(), Some(b' ' | b'\t' | b'\r' | b'"')) {
        return None;
    }
    number_from(cell, m, decimal_comma).map(|v| (v, end))
}

/// Whether `delim` can only end a number (not be part of one), so [`parse_leading_number`] may
/// find a cell's end: true for the comma, semicolon and tab delimiters of recordings (a comma
/// only without decimal commas).
#[inline]
pub(crate) fn delimiter_ends_numbers(delim: u8, decimal_comma: bool) -> bool {
    !(delim.is_ascii_digit()
        || matches!(delim, b'+' | b'-' | b'.')
        || (decimal_comma && delim == b','))
}

/// The sign and the digits of a cell up to its first non-digit after the optional fraction:
/// the mantissa as an integer (wrapping past 19 digits: callers check `int_digits +
/// frac_digits`), the digit counts from positions (not per-digit counters), and where the scan
/// stopped.
struct Mantissa {
    neg: bool,
    mant: u64,
    int_digits: usize,
    frac_digits: usize,
    end: usize,
}

impl Mantissa {
    /// Clinger's fast path (module docs): `±mant / 10^frac_digits` when there are 1–19 digits,
    /// the mantissa is below 2⁵³ and the power of ten at most 10²² — correctly rounded, as both
    /// operands are exact. `None` otherwise (the caller goes on with [`number_from`]).
    #[inline(always)]
    fn fast_value(&self) -> Option<f64> {
        let digits = self.int_digits + self.frac_digits;
        if digits == 0 || digits > 19 || self.mant >= (1u64 << 53) || self.frac_digits > 22 {
            return None;
        }
        let v = self.mant as f64 / POW10[self.frac_digits];
        Some(with_sign(v, self.neg))
    }
}

/// `-v` when `neg`, else `v`, for `v ≥ +0`: the sign bit set without a branch (a recording's
/// signs are as random as its noise, so a branch on them is mispredicted every other cell).
#[inline(always)]
fn with_sign(v: f64, neg: bool) -> f64 {
    f64::from_bits(v.to_bits() | (u64::from(neg) << 63))
}

/// Scan a trimmed cell's sign, integer and fraction digits (two tight digit loops, shared by
/// the inline fast path and the full parser; inlined into both).
#[inline(always)]
fn scan_mantissa(b: &[u8], decimal_comma: bool) -> Mantissa {
    let n = b.len();
    // the sign without a branch (random in recordings, see `with_sign`)
    let first = b.first().copied().unwrap_or(0);
    let neg = first == b'-';
    let mut i = usize::from(neg || first == b'+');
    let digits = |mut i: usize, mant: &mut u64| {
        while i < n {
            let d = b[i].wrapping_sub(b'0');
            if d >= 10 {
                break;
            }
            *mant = mant.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        i
    };
    let mut mant: u64 = 0;
    let int_start = i;
    i = digits(i, &mut mant);
    let int_digits = i - int_start;
    let mut frac_digits = 0;
    if i < n && (b[i] == b'.' || (decimal_comma && b[i] == b',')) {
        let frac_start = i + 1;
        i = digits(frac_start, &mut mant);
        frac_digits = i - frac_start;
    }
    Mantissa {
        neg,
        mant,
        int_digits,
        frac_digits,
        end: i,
    }
}

/// The rest of [`parse_number`] for a trimmed cell `b` whose mantissa scan gave `m`: exponents,
/// long mantissas and rejections.
#[cold]
#[inline(never)]
fn number_from(b: &[u8], m: Mantissa, decimal_comma: bool) -> Option<f64> {
    let n = b.len();
    let Mantissa {
        neg,
        mant,
        int_digits,
        frac_digits,
        end: mut i,
    } = m;
    if int_digits + frac_digits == 0 {
        return None;
    }
    let mut exp10 = -(frac_digits as i64);
    if i < n {
        if b[i] != b'e' && b[i] != b'E' {
            return None;
        }
        i += 1;
        let eneg = match b.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let start = i;
        let mut e: i64 = 0;
        while i < n && b[i].is_ascii_digit() {
            e = (e * 10 + i64::from(b[i] - b'0')).min(100_000);
            i += 1;
        }
        if i == start || i < n {
            return None;
        }
        exp10 += if eneg { -e } else { e };
    }
    if int_digits + frac_digits > 19 {
        // the mantissa may have wrapped (leading zeros included, conservatively)
        return slow_parse(b, decimal_comma);
    }
    let v = if mant == 0 {
        0.0
    } else if mant < (1u64 << 53) && (-22..=22).contains(&exp10) {
        let m = mant as f64;
        if exp10 < 0 {
            m / POW10[(-exp10) as usize]
        } else {
            m * POW10[exp10 as usize]
        }
    } else {
        return slow_parse(b, decimal_comma);
    };
    Some(if neg { -v } else { v })
}

/// Fallback: the standard library's correctly rounded parser (after mapping `,` to `.`).
fn slow_parse(b: &[u8], decimal_comma: bool) -> Option<f64> {
    let s: String = b
        .iter()
        .map(|&c| {
            if decimal_comma && c == b',' {
                '.'
            } else {
                c as char
            }
        })
        .collect();
    // reject forms std accepts but a recording cell must not contain
    if s.bytes()
        .any(|c| c.is_ascii_alphabetic() && c != b'e' && c != b'E')
    {
        return None;
    }
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Does the cell hold a number (used to classify header and unit rows)?
pub(crate) fn is_number(cell: &[u8], decimal_comma: bool) -> bool {
    parse_number(cell, decimal_comma).is_some()
}

/// Split a line on `delim`. Allocation-free iterator over the raw fields.
pub(crate) fn fields(line: &[u8], delim: u8) -> impl Iterator<Item = &[u8]> {
    line.split(move |&c| c == delim)
}

/// Why a line is not text, if it is not.
pub(crate) fn binary_issue(line: &[u8]) -> Option<String> {
    if let Some(p) = memchr::memchr(0, line) {
        return Some(format!("NUL byte at byte {} of the line", p + 1));
    }
    if let Some(p) = line
        .iter()
        .position(|&c| c < 0x20 && c != b'\t' && c != b'\r' && c != b'\n')
    {
        return Some(format!(
            "control character 0x{:02x} at byte {} of the line",
            line[p],
            p + 1
        ));
    }
    if let Err(e) = std::str::from_utf8(line) {
        // Windows-1252/Latin-1 header text (e.g. "Meßzeit") is accepted if it is sparse.
        let high = line.iter().filter(|&&c| c >= 0x80).count();
        if high * 10 > line.len() {
            return Some(format!(
                "invalid UTF-8 at byte {} of the line",
                e.valid_up_to() + 1
            ));
        }
    }
    None
}

/// Decode a header line: UTF-8, else Latin-1 (already checked by [`binary_issue`]).
pub(crate) fn decode(line: &[u8]) -> String {
    match std::str::from_utf8(line) {
        Ok(s) => s.to_string(),
        Err(_) => line.iter().map(|&c| c as char).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_parser_matches_std_on_common_and_edge_forms() {
        let cases = [
            "0",
            "-0",
            "1",
            "-12.345",
            "0.000001",
            "123456789012345678",
            "1234567890123456789012",
            "3.2e-05",
            "1E3",
            "+4.5",
            "0.1",
            "0.30000000000000004",
            "9007199254740993",
            "1e22",
            "1e23",
            "4.9e-324",
            "1.7976931348623157e308",
            " 2.5 ",
            "\"7.25\"",
            ".5",
            "5.",
        ];
        for c in cases {
            let expect: f64 = c.trim().trim_matches('"').parse().unwrap();
            assert_eq!(parse_number(c.as_bytes(), false), Some(expect), "{c}");
        }
    }

    #[test]
    fn decimal_comma_and_rejections() {
        assert_eq!(parse_number(b"-1,25", true), Some(-1.25));
        assert_eq!(parse_number(b"-1,25", false), None);
        for bad in [
            "", "-", "abc", "1.2.3", "nan", "inf", "1e", "1e+", "1x", "1e400", "--1",
        ] {
            assert_eq!(parse_number(bad.as_bytes(), true), None, "{bad}");
        }
    }

    /// `parse_number` against the standard library (correctly rounded) on one string: the same
    /// bits where std gives a finite number, `None` where it fails or is not finite.
    fn agrees_with_std(s: &str) -> Result<(), proptest::test_runner::TestCaseError> {
        let expect = s.parse::<f64>().ok().filter(|v| v.is_finite());
        let got = parse_number(s.as_bytes(), false);
        proptest::prop_assert_eq!(got.map(f64::to_bits), expect.map(f64::to_bits), "{:?}", s);
        // the same with a decimal comma
        let comma = s.replace('.', ",");
        let got = parse_number(comma.as_bytes(), true);
        proptest::prop_assert_eq!(
            got.map(f64::to_bits),
            expect.map(f64::to_bits),
            "{:?}",
            comma
        );
        Ok(())
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4000))]

        /// Any string over the number alphabet (most are not numbers): same verdict and bits.
        #[test]
        fn parser_equals_std_on_random_strings(s in "[-+0-9.eE]{0,30}") {
            agrees_with_std(&s)?;
        }

        /// Number-shaped strings: sign, up to 25 integer and 25 fraction digits (long mantissas
        /// and leading zeros go through the fallback), optional exponent up to ±400.
        #[test]
        fn parser_equals_std_on_number_forms(
            s in "[-+]?[0-9]{0,25}(\\.[0-9]{0,25})?([eE][-+]?[0-9]{1,3})?"
        ) {
            agrees_with_std(&s)?;
        }

        /// Random doubles printed as a recording would hold them: shortest round trip,
        /// scientific, and fixed with 0–12 decimals.
        #[test]
        fn parser_equals_std_on_printed_doubles(bits in proptest::num::u64::ANY, d in 0usize..13) {
            let v = f64::from_bits(bits);
            if v.is_finite() {
                agrees_with_std(&format!("{v}"))?;
                agrees_with_std(&format!("{v:e}"))?;
                if v.abs() < 1e30 {
                    agrees_with_std(&format!("{v:.d$}"))?;
                }
            }
        }

        /// Magnitudes of measured forces (the fast path): 1–17 significant digits.
        #[test]
        fn parser_equals_std_on_force_like_values(v in -1e5f64..1e5, d in 0usize..17) {
            agrees_with_std(&format!("{v:.d$}"))?;
        }
    }

    /// [`parse_leading_number`] on `row` against splitting the first cell off at `delim` and
    /// [`parse_number`]: when it accepts a cell, the same end and the same bits.
    fn leading_agrees_with_split(
        row: &str,
        delim: u8,
        dc: bool,
    ) -> Result<(), proptest::test_runner::TestCaseError> {
        let b = row.as_bytes();
        if let Some((v, len)) = parse_leading_number(b, delim, dc) {
            let end = b.iter().position(|&c| c == delim).unwrap_or(b.len());
            proptest::prop_assert_eq!(len, end, "{:?}", row);
            let split = parse_number(&b[..end], dc).map(f64::to_bits);
            proptest::prop_assert_eq!(Some(v.to_bits()), split, "{:?}", row);
        }
        Ok(())
    }

    #[test]
    fn leading_number_takes_common_cells_and_leaves_the_rest() {
        assert_eq!(
            parse_leading_number(b"-12.5,3", b',', false),
            Some((-12.5, 5))
        );
        assert_eq!(
            parse_leading_number(b"0.0001", b',', false),
            Some((1e-4, 6))
        );
        assert_eq!(
            parse_leading_number(b"-1,25;7", b';', true),
            Some((-1.25, 5))
        );
        // exponents go on from the digit scan (the scientific exports of some programs)
        assert_eq!(
            parse_leading_number(b"-1.5e3,2", b',', false),
            Some((-1500.0, 6))
        );
        assert_eq!(
            parse_leading_number(b"2,5E-2;1", b';', true),
            Some((0.025, 6))
        );
        // blanks, quotes, text, invalid forms and empty cells are left to the split-and-parse path
        for rest in [
            " 1,2", "\"1\",2", "1e3 ,2", "1 ,2", "x,2", ",2", "", "-,2", "1\r", "1.2.3,4", "1e,2",
        ] {
            assert_eq!(
                parse_leading_number(rest.as_bytes(), b',', false),
                None,
                "{rest:?}"
            );
        }
        for d in [b'0', b'9', b'+', b'-', b'.'] {
            assert!(!delimiter_ends_numbers(d, false));
        }
        assert!(delimiter_ends_numbers(b',', false) && !delimiter_ends_numbers(b',', true));
        assert!(delimiter_ends_numbers(b';', true) && delimiter_ends_numbers(b'\t', true));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(4000))]

        /// Rows over the number alphabet, blanks, quotes and the delimiters: the one-pass cell
        /// equals split + parse wherever it answers.
        #[test]
        fn leading_number_equals_split_then_parse(row in "[-+0-9.,;eE \t\"x]{0,24}") {
            leading_agrees_with_split(&row, b',', false)?;
            leading_agrees_with_split(&row, b';', true)?;
            leading_agrees_with_split(&row, b'\t', true)?;
        }

        /// A common cell ended by the delimiter or a line end: wherever it answers, the byte
        /// that ended it is the one after the cell, and the value is `parse_number`'s of the
        /// cell, bit for bit; force-like cells are always taken (issue 18).
        #[test]
        fn common_cell_equals_parse_number(row in "[-+0-9.,;eE \t\"x\r\n]{0,24}", v in -1e5f64..1e5, d in 0usize..9, end in "[,;\r\n]") {
            for (delim, dc) in [(b',', false), (b';', true), (b'\t', true)] {
                let b = row.as_bytes();
                if let Some((x, len, e)) = parse_common_cell(b, delim, dc) {
                    proptest::prop_assert_eq!(b[len], e);
                    proptest::prop_assert!(e == delim || e == b'\n' || e == b'\r');
                    proptest::prop_assert_eq!(parse_number(&b[..len], dc).map(f64::to_bits), Some(x.to_bits()), "{:?}", row);
                }
            }
            let cell = format!("{v:.d$}{end}");
            let delim = if end == ";" { b';' } else { b',' };
            let got = parse_common_cell(cell.as_bytes(), delim, false);
            let want = cell[..cell.len() - 1].parse::<f64>().unwrap();
            proptest::prop_assert_eq!(got.map(|(x, len, _)| (x.to_bits(), len)), Some((want.to_bits(), cell.len() - 1)), "{:?}", cell);
        }

        /// Force-like cells followed by a delimiter and more cells: always taken, same bits.
        #[test]
        fn leading_number_takes_force_like_cells(v in -1e5f64..1e5, d in 0usize..17, tail in "[,;0-9.]{0,8}") {
            let row = format!("{v:.d$}{tail}");
            for (delim, dc) in [(b',', false), (b';', false)] {
                let cell_end = row.bytes().position(|c| c == delim).unwrap_or(row.len());
                if row[..cell_end].bytes().all(|c| c.is_ascii_digit() || c == b'.' || c == b'-')
                    && row[..cell_end].bytes().filter(|&c| c == b'.').count() <= 1
                    && row[..cell_end].bytes().filter(|c| c.is_ascii_digit()).count() <= 15
                {
                    proptest::prop_assert!(parse_leading_number(row.as_bytes(), delim, dc).is_some(), "{:?}", row);
                }
                leading_agrees_with_split(&row, delim, dc)?;
            }
        }
    }

    #[test]
    fn binary_detection() {
        assert!(binary_issue(b"1,2\x003").is_some());
        assert!(binary_issue(b"\xff\xfe\xfd\xfc").is_some());
        assert!(binary_issue(b"Me\xdfzeit [s]:,50").is_none());
        assert!(binary_issue(b"Time\tFx").is_none());
    }
}
