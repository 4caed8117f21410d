//! PNG at the fast level, compressed in strips of rows on every core.
//!
//! A PNG's image data is one zlib stream, but deflate lets a stream be cut at byte boundaries
//! between blocks, so strips of rows can be compressed independently and concatenated (as
//! pigz and mtpng do). Each strip's rows are filtered by the row above (`Up`; a strip's first
//! row by the last row of the strip before it, which the strip quantises itself) and deflated
//! by `fdeflate`, the same compressor the `png` crate uses at this level, into one Huffman
//! block; an empty stored block after it (a sync flush) brings the stream back to a byte
//! boundary. A strip that would come out larger than its bytes stored (noise) is stored
//! instead. The stream ends with an empty final block and the Adler-32 of all the filtered
//! bytes, combined from the strips' own checksums. Each strip is one `IDAT` chunk.
//!
//! `fdeflate` writes a whole zlib stream, so a strip's bytes are that stream with its framing
//! changed: the two header bytes dropped (but for the first strip), the block's final bit
//! cleared, the trailing checksum taken off. Where its block ends within the last byte is
//! where that byte's highest set bit is: the block ends with the end-of-block code, whose
//! last bit is 1 in `fdeflate`'s fixed code table, and only zero padding follows it. The
//! round-trip tests decode the result with the `png` crate, so a release of `fdeflate` that
//! changed this would fail them.

use std::ops::Range;

use rayon::prelude::*;

/// Rows compressed as one unit: 32 rows of a 1080p frame are 184 kB, so the frame's 34 strips
/// balance over the cores to within about a quarter of a millisecond, and each strip's framing
/// (about 60 bytes: its code table and the stored block) is 0.4 % of the koala's file.
const ROWS_PER_STRIP: u32 = 32;

/// PNG's filter type `Up`: each byte minus the byte above it.
const FILTER_UP: u8 = 2;

/// The zlib header `fdeflate` writes: deflate, 32 kB window, fastest level.
const ZLIB_HEADER: [u8; 2] = [0x78, 0x01];

/// A final, empty block with the fixed code: the final bit, type 01, the end-of-block code
/// (seven zero bits), padded to the byte.
const FINAL_EMPTY_BLOCK: [u8; 2] = [0x03, 0x00];

/// The largest stored block's length.
const MAX_STORED_BLOCK: usize = 65_535;

/// The Adler-32 modulus.
const ADLER_MODULUS: u32 = 65_521;

/// An 8-bit RGB image of `width` × `height` as PNG bytes; `fill_row(y, levels)` writes row
/// `y`'s `3 · width` levels and may be called for any row from any thread (a strip asks for
/// the row above its first too).
pub(super) fn encode(
    width: u32,
    height: u32,
    fill_row: impl Fn(u32, &mut [u8]) + Sync,
) -> Result<Vec<u8>, png::EncodingError> {
    let row_bytes = width as usize * 3;
    let strip_count = height.div_ceil(ROWS_PER_STRIP);
    let mut strips: Vec<Strip> = (0..strip_count)
        .into_par_iter()
        .map_init(
            || StripScratch::new(row_bytes),
            |scratch, strip| {
                let first = strip * ROWS_PER_STRIP;
                let rows = first..height.min(first + ROWS_PER_STRIP);
                scratch.compress(rows, &fill_row, strip == 0)
            },
        )
        .collect();
    let checksum = strips.iter().fold(adler32_of_nothing(), |checksum, strip| {
        adler32_combine(checksum, strip.checksum, strip.filtered_len)
    });
    let mut end = FINAL_EMPTY_BLOCK.to_vec();
    end.extend_from_slice(&checksum.to_be_bytes());
    match strips.last_mut() {
        Some(last) => last.bytes.extend_from_slice(&end),
        None => strips.push(Strip {
            bytes: [ZLIB_HEADER.as_slice(), &end].concat(),
            checksum: adler32_of_nothing(),
            filtered_len: 0,
        }),
    }

    let compressed_len: usize = strips.iter().map(|strip| strip.bytes.len()).sum();
    // Signature, IHDR and IEND are 57 bytes; each IDAT adds 12.
    let mut png_bytes = Vec::with_capacity(compressed_len + 57 + 12 * strips.len());
    let mut encoder = png::Encoder::new(&mut png_bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    for strip in &strips {
        writer.write_chunk(png::chunk::IDAT, &strip.bytes)?;
    }
    writer.finish()?;
    Ok(png_bytes)
}

/// One strip's part of the zlib stream, ending at a byte boundary.
struct Strip {
    bytes: Vec<u8>,
    /// The Adler-32 of the strip's filtered bytes.
    checksum: u32,
    filtered_len: usize,
}

/// Buffers reused from strip to strip (rayon makes one set per piece of work it splits off).
struct StripScratch {
    /// The row above the one being filtered, and that row, as levels.
    above: Vec<u8>,
    current: Vec<u8>,
    /// The strip's filtered rows, each its filter type and `row_bytes` bytes.
    filtered: Vec<u8>,
}

impl StripScratch {
    fn new(row_bytes: usize) -> StripScratch {
        StripScratch {
            above: vec![0; row_bytes],
            current: vec![0; row_bytes],
            filtered: Vec::with_capacity((row_bytes + 1) * ROWS_PER_STRIP as usize),
        }
    }

    /// Quantises, filters and compresses `rows`; the first strip starts the zlib stream.
    fn compress(&mut self, rows: Range<u32>, fill_row: &impl Fn(u32, &mut [u8]), first_strip: bool) -> Strip {
        // The first row of the image is filtered against a row of zeros, as PNG decodes it.
        match rows.start.checked_sub(1) {
            Some(above) => fill_row(above, &mut self.above),
            None => self.above.fill(0),
        }
        self.filtered.clear();
        for y in rows {
            fill_row(y, &mut self.current);
            self.filtered.push(FILTER_UP);
            self.filtered.extend(
                self.current
                    .iter()
                    .zip(&self.above)
                    .map(|(&level, &above)| level.wrapping_sub(above)),
            );
            std::mem::swap(&mut self.current, &mut self.above);
        }
        let mut bytes = match deflate_block(&self.filtered) {
            Some(block) if block.len() <= stored_len(self.filtered.len()) + ZLIB_HEADER.len() => block,
            _ => stored_blocks(&self.filtered),
        };
        let checksum = adler32(&self.filtered);
        if !first_strip {
            bytes.drain(..ZLIB_HEADER.len());
        }
        Strip {
            bytes,
            checksum,
            filtered_len: self.filtered.len(),
        }
    }
}

/// `data` as `fdeflate` compresses it, after the zlib header: one non-final block and an
/// empty stored block that ends it at a byte boundary. `None` if `fdeflate`'s stream is not
/// framed as expected (a zlib header, a dynamic block marked final, a nonzero last byte).
fn deflate_block(data: &[u8]) -> Option<Vec<u8>> {
    const CHECKSUM_LEN: usize = 4;
    /// The first three bits of `fdeflate`'s block: final, type 10 (dynamic codes).
    const FINAL_DYNAMIC_BLOCK: u8 = 0b101;
    let mut compressor = fdeflate::Compressor::new(Vec::with_capacity(data.len() / 4)).ok()?;
    compressor.write_data(data).ok()?;
    let mut bytes = compressor.finish().ok()?;
    bytes.truncate(bytes.len().checked_sub(CHECKSUM_LEN)?);
    let framed_as_expected = bytes.starts_with(&ZLIB_HEADER)
        && bytes
            .get(ZLIB_HEADER.len())
            .is_some_and(|&first| first & 0b111 == FINAL_DYNAMIC_BLOCK)
        && bytes.last().is_some_and(|&last| last != 0);
    if !framed_as_expected {
        return None;
    }
    bytes[ZLIB_HEADER.len()] &= !1;
    // The padding above the end-of-block code's last (set) bit: room for the stored block's
    // three header bits (not final, type 00, all zero), or a byte more for them.
    let padding_bits = bytes[bytes.len() - 1].leading_zeros();
    if padding_bits < 3 {
        bytes.push(0);
    }
    // The empty stored block's length and its complement.
    bytes.extend_from_slice(&[0x00, 0x00, 0xff, 0xff]);
    Some(bytes)
}

/// The length of `len` bytes in stored blocks.
fn stored_len(len: usize) -> usize {
    len + 5 * len.div_ceil(MAX_STORED_BLOCK)
}

/// `data` in non-final stored blocks, after a zlib header.
fn stored_blocks(data: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(ZLIB_HEADER.len() + stored_len(data.len()));
    bytes.extend_from_slice(&ZLIB_HEADER);
    for block in data.chunks(MAX_STORED_BLOCK) {
        let len = block.len() as u16;
        // Not final, type 00, padded to the byte; then the length and its complement.
        bytes.push(0);
        bytes.extend_from_slice(&len.to_le_bytes());
        bytes.extend_from_slice(&(!len).to_le_bytes());
        bytes.extend_from_slice(block);
    }
    bytes
}

fn adler32(data: &[u8]) -> u32 {
    let mut hasher = simd_adler32::Adler32::new();
    hasher.write(data);
    hasher.finish()
}

/// The Adler-32 of no bytes.
fn adler32_of_nothing() -> u32 {
    1
}

/// The Adler-32 of `a` followed by `b` from theirs and `b`'s length (zlib's
/// `adler32_combine`): `b`'s first sum shifts by `a`'s, its second by `a`'s first sum once per
/// byte of `b` and by `a`'s second.
fn adler32_combine(checksum_a: u32, checksum_b: u32, len_b: usize) -> u32 {
    let modulus = u64::from(ADLER_MODULUS);
    let (low_a, high_a) = (u64::from(checksum_a & 0xffff), u64::from(checksum_a >> 16));
    let (low_b, high_b) = (u64::from(checksum_b & 0xffff), u64::from(checksum_b >> 16));
    let len_b = len_b as u64 % modulus;
    // `low_b` counts the initial 1 that `low_a` counts already.
    let low = (low_a + low_b + modulus - 1) % modulus;
    let high = (high_a + high_b + len_b * low_a % modulus + modulus - len_b) % modulus;
    (high << 16 | low) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic byte pattern: xorshift.
    fn noise(len: usize, seed: u64) -> Vec<u8> {
        let mut rng = crate::test_support::XorShift64::new(seed | 1);
        (0..len)
            .map(|_| {
                let state = rng.next_u64();
                state as u8
            })
            .collect()
    }

    fn decode(png_bytes: &[u8]) -> (u32, u32, Vec<u8>) {
        let decoder = png::Decoder::new(std::io::Cursor::new(png_bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        pixels.truncate(info.buffer_size());
        (info.width, info.height, pixels)
    }

    fn round_trip(width: u32, height: u32, pixels: &[u8]) {
        let row_bytes = width as usize * 3;
        let png_bytes = encode(width, height, |y, row| {
            row.copy_from_slice(&pixels[y as usize * row_bytes..][..row_bytes]);
        })
        .unwrap();
        let (decoded_width, decoded_height, decoded) = decode(&png_bytes);
        assert_eq!((decoded_width, decoded_height), (width, height));
        assert!(decoded == pixels, "{width}×{height}: pixels differ");
        // The stream's Adler-32 checks out too (the `png` crate's decoder skips it).
        let idat: Vec<u8> = idat_data(&png_bytes);
        let inflated = fdeflate::decompress_to_vec(&idat).expect("a valid zlib stream");
        assert_eq!(inflated.len(), (row_bytes + 1) * height as usize);
    }

    /// The concatenated data of `png_bytes`' IDAT chunks.
    fn idat_data(png_bytes: &[u8]) -> Vec<u8> {
        let mut data = Vec::new();
        let mut rest = &png_bytes[8..];
        while rest.len() >= 12 {
            let len = u32::from_be_bytes(rest[..4].try_into().unwrap()) as usize;
            if &rest[4..8] == b"IDAT" {
                data.extend_from_slice(&rest[8..8 + len]);
            }
            rest = &rest[12 + len..];
        }
        data
    }

    /// Odd sizes, one row, one column, exactly one strip and one row over, many strips; all
    /// black (one long zero run per row), noise (stored strips), and smooth gradients
    /// (compressed strips) side by side.
    #[test]
    fn strips_decode_to_the_exact_pixels() {
        let strip = ROWS_PER_STRIP;
        let sizes = [
            (1, 1),
            (1, 1000),
            (1000, 1),
            (7, 3),
            (13, strip),
            (13, strip + 1),
            (61, 5 * strip - 1),
            (333, 3 * strip + 17),
        ];
        for (width, height) in sizes {
            let len = width as usize * height as usize * 3;
            round_trip(width, height, &vec![0; len]);
            round_trip(width, height, &noise(len, u64::from(width * height)));
            let gradient: Vec<u8> = (0..len).map(|i| ((i / 3) % 251 + i % 3 * 4) as u8).collect();
            round_trip(width, height, &gradient);
            // Noise above, a gradient below: strips of both kinds in one stream.
            let mut mixed = noise(len / 2, 7);
            mixed.extend_from_slice(&gradient[len / 2..]);
            round_trip(width, height, &mixed);
        }
    }

    /// Every padding `fdeflate` can leave after its block (zero to seven bits) is closed
    /// correctly, and noise is stored, not inflated.
    #[test]
    fn every_block_end_within_a_byte() {
        let mut paddings_seen = [false; 8];
        for len in 1..200 {
            let data: Vec<u8> = (0..len).map(|i| (i * 7 % 13) as u8).collect();
            let mut compressor = fdeflate::Compressor::new(Vec::new()).unwrap();
            compressor.write_data(&data).unwrap();
            let whole = compressor.finish().unwrap();
            paddings_seen[whole[whole.len() - 5].leading_zeros() as usize] = true;
            let mut stream = deflate_block(&data).unwrap();
            stream.extend_from_slice(&FINAL_EMPTY_BLOCK);
            stream.extend_from_slice(&adler32(&data).to_be_bytes());
            assert_eq!(fdeflate::decompress_to_vec(&stream).unwrap(), data, "{len} bytes");
        }
        assert!(paddings_seen.iter().all(|&seen| seen), "{paddings_seen:?}");

        let (width, height) = (100, 3 * ROWS_PER_STRIP);
        let raw_len = (width as usize * 3 + 1) * height as usize;
        let pixels = noise(width as usize * 3 * height as usize, 11);
        let png_bytes = encode(width, height, |y, row| {
            row.copy_from_slice(&pixels[y as usize * row.len()..][..row.len()]);
        })
        .unwrap();
        assert!(
            png_bytes.len() < raw_len + 200,
            "{} bytes for {raw_len}",
            png_bytes.len()
        );
    }

    #[test]
    fn adler32_combines_like_one_pass() {
        let data = noise(200_000, 3);
        for split in [0, 1, 2, 65_520, 65_521, 65_522, 131_043, 199_999, 200_000] {
            let (a, b) = data.split_at(split);
            assert_eq!(
                adler32_combine(adler32(a), adler32(b), b.len()),
                adler32(&data),
                "split at {split}"
            );
        }
        let ones = vec![0xff; 300_000];
        let (a, b) = ones.split_at(123_457);
        assert_eq!(adler32_combine(adler32(a), adler32(b), b.len()), adler32(&ones));
    }
}
