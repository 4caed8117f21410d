//! Escaping for the XML and HTML that `check` writes (JUnit files, the HTML report).
//!
//! `&`, `<`, `>`, `"` and `'` become entity references, valid in XML 1.0 and HTML5 alike.
//! Characters XML 1.0 forbids even as references (NUL, ANSI escape sequences from coloured
//! output, other C0 controls) become U+FFFD, so a stray byte in a diagnostic cannot make a CI
//! system reject the whole file.
//!
//! [`data_url`] embeds a file in the report page itself (base64), so the page is one file.

/// `text` made safe for an XML attribute value.
pub fn attribute(text: &str) -> String {
    escape_xml(text, true)
}

/// `text` made safe for XML element content (line breaks stay line breaks).
pub fn text(text: &str) -> String {
    escape_xml(text, false)
}

fn escape_xml(text: &str, attribute: bool) -> String {
    let mut escaped = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => escaped.push_str("&amp;"),
            '<' => escaped.push_str("&lt;"),
            '>' => escaped.push_str("&gt;"),
            '"' => escaped.push_str("&quot;"),
            '\'' => escaped.push_str("&apos;"),
            // Attribute values would turn raw line breaks and tabs into spaces.
            '\n' | '\r' | '\t' if !attribute => escaped.push(c),
            '\n' => escaped.push_str("&#10;"),
            '\r' => escaped.push_str("&#13;"),
            '\t' => escaped.push_str("&#9;"),
            // Not allowed anywhere in XML 1.0, not even as references: ANSI escapes, NUL.
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => escaped.push('\u{FFFD}'),
            c => escaped.push(c),
        }
    }
    escaped
}

/// `bytes` as a `data:` URL of type `mime` (standard base64, padded).
pub fn data_url(mime: &str, bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut url = String::with_capacity(mime.len() + 13 + bytes.len().div_ceil(3) * 4);
    url.push_str("data:");
    url.push_str(mime);
    url.push_str(";base64,");
    for group in bytes.chunks(3) {
        let joined = group.iter().enumerate().fold(0u32, |joined, (i, &byte)| {
            joined | u32::from(byte) << (16 - 8 * i)
        });
        for position in 0..4 {
            if position <= group.len() {
                let sextet = (joined >> (18 - 6 * position)) & 63;
                url.push(char::from(ALPHABET[sextet as usize]));
            } else {
                url.push('=');
            }
        }
    }
    url
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_urls_are_padded_base64() {
        // RFC 4648's test vectors.
        for (bytes, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(
                data_url("text/plain", bytes.as_bytes()),
                format!("data:text/plain;base64,{encoded}")
            );
        }
        assert_eq!(data_url("a/b", &[0xff, 0xfe]), "data:a/b;base64,//4=");
    }

    #[test]
    fn escaping_covers_markup_and_forbidden_characters() {
        assert_eq!(
            attribute("a<b>&\"c\" 'd'\n\u{1b}[31m"),
            "a&lt;b&gt;&amp;&quot;c&quot; &apos;d&apos;&#10;\u{FFFD}[31m"
        );
        assert_eq!(attribute("plain ✓"), "plain ✓");
        assert_eq!(text("two\nlines & <more>"), "two\nlines &amp; &lt;more&gt;");
    }
}
