//! The bounded byte reader every parse goes through, and its error type.

pub(super) enum GridError {
    /// Malformed or truncated data.
    Format(String),
    /// A valid file using a feature this reader does not handle.
    Unsupported(String),
}
impl From<String> for GridError {
    fn from(m: String) -> Self {
        GridError::Format(m)
    }
}

/// A bounds-checked cursor over the file's bytes.
pub(super) struct Reader<'a> {
    pub(super) b: &'a [u8],
    pub(super) pos: usize,
}

impl<'a> Reader<'a> {
    pub(super) fn take(&mut self, n: u64) -> std::result::Result<&'a [u8], String> {
        let left = (self.b.len() - self.pos) as u64;
        if n > left {
            return Err(format!(
                "truncated: {n} bytes needed at offset {}, {left} left",
                self.pos
            ));
        }
        let s = &self.b[self.pos..self.pos + n as usize];
        self.pos += n as usize;
        Ok(s)
    }
    pub(super) fn seek(&mut self, pos: u64) -> std::result::Result<(), String> {
        if pos > self.b.len() as u64 {
            return Err(format!(
                "offset {pos} lies past the end of the file ({} bytes)",
                self.b.len()
            ));
        }
        self.pos = pos as usize;
        Ok(())
    }
    pub(super) fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    pub(super) fn u32(&mut self) -> std::result::Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    pub(super) fn i32(&mut self) -> std::result::Result<i32, String> {
        Ok(i32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    pub(super) fn i64(&mut self) -> std::result::Result<i64, String> {
        Ok(i64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    pub(super) fn f32(&mut self) -> std::result::Result<f32, String> {
        Ok(f32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    pub(super) fn f64(&mut self) -> std::result::Result<f64, String> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    pub(super) fn vec3d(&mut self) -> std::result::Result<[f64; 3], String> {
        Ok([self.f64()?, self.f64()?, self.f64()?])
    }
    pub(super) fn string(&mut self) -> std::result::Result<String, String> {
        let n = self.u32()?;
        let s = self.take(n as u64)?;
        Ok(String::from_utf8_lossy(s).into_owned())
    }
    pub(super) fn mask(
        &mut self,
        words: usize,
        out: &mut Vec<u64>,
    ) -> std::result::Result<(), String> {
        let s = self.take(8 * words as u64)?;
        out.clear();
        out.extend(
            s.chunks_exact(8)
                .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))),
        );
        Ok(())
    }
}
