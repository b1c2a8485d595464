//! Provenance in the plots' metadata (issue 21 item 6): a front end sets one text per run
//! ([`set`], or [`set_provider`] for a text computed when the first plot is written — the CLI
//! hashes the inputs in the background) — tool version, command line, inputs and their hashes —
//! and every plot written after that carries it: SVG as a `<metadata>` element (after the opening `<svg …>` tag), PNG as a
//! `tEXt` chunk with the keyword `runout-provenance` (after `IHDR`; PNG spec §11.3.4.3). Without
//! [`set`], plots are written unchanged.

use std::path::Path;
use std::sync::RwLock;

/// Computes the text when a plot is written.
pub type Provider = Box<dyn Fn() -> Option<String> + Send + Sync>;

static PROVIDER: RwLock<Option<Provider>> = RwLock::new(None);

/// The PNG `tEXt` keyword (1–79 Latin-1 characters).
pub const PNG_KEYWORD: &str = "runout-provenance";

/// Sets the text embedded in every plot written from now on (`None`: none).
pub fn set(text: Option<String>) {
    set_provider(text.map(|t| Box::new(move || Some(t.clone())) as Provider));
}

/// Sets the function that gives the text when a plot is written (`None`: no text).
pub fn set_provider(provider: Option<Provider>) {
    *PROVIDER.write().unwrap_or_else(|e| e.into_inner()) = provider;
}

/// The text embedded in plots, if set.
pub fn get() -> Option<String> {
    PROVIDER
        .read()
        .unwrap_or_else(|e| e.into_inner())
        .as_ref()
        .and_then(|f| f())
}

/// Embeds the text (if set) into the finished plot file `path` of `format`.
pub fn embed(path: &Path, format: super::Format) -> std::io::Result<()> {
    let Some(text) = get() else { return Ok(()) };
    let bytes = std::fs::read(path)?;
    let out = match format {
        super::Format::Svg => svg_with(&bytes, &text),
        super::Format::Png => png_with(&bytes, &text),
    };
    match out {
        Some(out) => std::fs::write(path, out),
        None => Ok(()),
    }
}

/// The SVG with `<metadata>` (XML-escaped text) after its opening tag; `None` if no `<svg` tag.
pub fn svg_with(svg: &[u8], text: &str) -> Option<Vec<u8>> {
    let s = std::str::from_utf8(svg).ok()?;
    let start = s.find("<svg")?;
    let end = start + s[start..].find('>')? + 1;
    let escaped = text
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let mut out = String::with_capacity(s.len() + escaped.len() + 40);
    out.push_str(&s[..end]);
    out.push_str("\n<metadata id=\"runout-provenance\">");
    out.push_str(&escaped);
    out.push_str("</metadata>");
    out.push_str(&s[end..]);
    Some(out.into_bytes())
}

/// The PNG with a `tEXt` chunk (`runout-provenance`, text as Latin-1 with other characters as `?`)
/// after `IHDR`; `None` if the bytes are not a PNG starting with `IHDR`.
pub fn png_with(png: &[u8], text: &str) -> Option<Vec<u8>> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    if !png.starts_with(SIGNATURE) || png.get(12..16)? != b"IHDR" {
        return None;
    }
    let ihdr_len = u32::from_be_bytes(png.get(8..12)?.try_into().ok()?) as usize;
    let after_ihdr = 8 + 12 + ihdr_len;
    let mut data = Vec::with_capacity(PNG_KEYWORD.len() + 1 + text.len());
    data.extend_from_slice(PNG_KEYWORD.as_bytes());
    data.push(0);
    data.extend(
        text.chars()
            .map(|c| u8::try_from(u32::from(c)).unwrap_or(b'?')),
    );
    let mut chunk = Vec::with_capacity(12 + data.len());
    chunk.extend_from_slice(&(data.len() as u32).to_be_bytes());
    chunk.extend_from_slice(b"tEXt");
    chunk.extend_from_slice(&data);
    let mut crc = crc32fast::Hasher::new();
    crc.update(b"tEXt");
    crc.update(&data);
    chunk.extend_from_slice(&crc.finalize().to_be_bytes());
    let mut out = Vec::with_capacity(png.len() + chunk.len());
    out.extend_from_slice(png.get(..after_ihdr)?);
    out.extend_from_slice(&chunk);
    out.extend_from_slice(png.get(after_ihdr..)?);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_gets_escaped_metadata_after_its_tag() {
        let svg = br#"<?xml version="1.0"?><svg width="10" height="10"><rect/></svg>"#;
        let out = String::from_utf8(svg_with(svg, "runout 0.1 a<b & c").unwrap()).unwrap();
        assert!(out.contains(r#"<svg width="10" height="10">"#));
        assert!(out.contains(
            "<metadata id=\"runout-provenance\">runout 0.1 a&lt;b &amp; c</metadata><rect/>"
        ));
        assert!(svg_with(b"not svg", "x").is_none());
    }

    #[test]
    fn png_text_chunk_has_a_valid_crc_after_ihdr() {
        // a 1×1 grey PNG (IHDR, IDAT, IEND)
        let png: &[u8] = &[
            0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13, b'I', b'H', b'D', b'R', 0,
            0, 0, 1, 0, 0, 0, 1, 8, 0, 0, 0, 0, 0x3a, 0x7e, 0x9b, 0x55, 0, 0, 0, 10, b'I', b'D',
            b'A', b'T', 0x78, 0x9c, 0x63, 0x60, 0, 0, 0, 2, 0, 1, 0xe5, 0x27, 0xde, 0xfc, 0, 0, 0,
            0, b'I', b'E', b'N', b'D', 0xae, 0x42, 0x60, 0x82,
        ];
        let out = png_with(png, "runout 0.1 µ").unwrap();
        let at = 8 + 25;
        let len = u32::from_be_bytes(out[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(&out[at + 4..at + 8], b"tEXt");
        let data = &out[at + 8..at + 8 + len];
        assert_eq!(data, b"runout-provenance\0runout 0.1 \xb5");
        let crc = u32::from_be_bytes(out[at + 8 + len..at + 12 + len].try_into().unwrap());
        let mut h = crc32fast::Hasher::new();
        h.update(b"tEXt");
        h.update(data);
        assert_eq!(crc, h.finalize());
        assert_eq!(&out[at + 12 + len..], &png[at..]);
        // the IHDR CRC of the original is valid (the fixture is a real PNG)
        let mut h = crc32fast::Hasher::new();
        h.update(&png[12..29]);
        assert_eq!(h.finalize(), 0x3a7e9b55);
        assert!(png_with(b"GIF89a", "x").is_none());
    }
}
