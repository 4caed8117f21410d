//! Escaping for the XML and HTML that `check` writes (JUnit files, the HTML report).
//!
//! `&`, `<`, `>`, `"` and `'` become entity references, valid in XML 1.0 and HTML5 alike.
//! Characters XML 1.0 forbids even as references (NUL, ANSI escape sequences from coloured
//! output, other C0 controls) become U+FFFD, so a stray byte in a diagnostic cannot make a CI
//! system reject the whole file.

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

#[cfg(test)]
mod tests {
    use super::*;

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
