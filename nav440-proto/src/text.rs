//! Diagnostic texts written once for two formatters: `core::fmt` (the `Display` impls the host
//! prints) and defmt (the `defmt::Format` impls a firmware sends, which the host renders to the
//! same text). A firmware that prints a [`BootError`](crate::boot::BootError) through defmt so
//! links no `core::fmt` machinery, and no text: the fixed pieces ([`lit!`]) are interned
//! strings of defmt's table, which the host reads from the ELF (they take no flash).

use core::fmt;

/// A fixed piece of text as the sink takes it: the literal for `core::fmt`, and with the
/// feature `defmt` its interned form as well.
#[cfg(feature = "defmt")]
pub(crate) type Interned = defmt::Str;
/// A fixed piece of text as the sink takes it: the literal only (no feature `defmt`).
#[cfg(not(feature = "defmt"))]
pub(crate) type Interned = ();

/// Appends the string literal `$s` to the sink `$w` ([`Text::lit`]).
#[cfg(feature = "defmt")]
macro_rules! lit {
    ($w:expr, $s:literal) => {
        $w.lit($s, defmt::intern!($s))
    };
}
/// Appends the string literal `$s` to the sink `$w` ([`Text::lit`]).
#[cfg(not(feature = "defmt"))]
macro_rules! lit {
    ($w:expr, $s:literal) => {
        $w.lit($s, ())
    };
}
pub(crate) use lit;

/// A sink for the pieces of a diagnostic line: text, decimal numbers, four hex digits.
pub(crate) trait Text {
    /// Appends `s`.
    fn str(&mut self, s: &str) -> fmt::Result;
    /// Appends the fixed piece `s`, interned as `i` ([`lit!`]).
    fn lit(&mut self, s: &'static str, i: Interned) -> fmt::Result;
    /// Appends `v` in decimal.
    fn dec(&mut self, v: u32) -> fmt::Result;
    /// Appends `v` as four upper-case hex digits (`0x` not included).
    fn hex4(&mut self, v: u16) -> fmt::Result {
        const DIGITS: &str = "0123456789ABCDEF";
        for shift in [12, 8, 4, 0] {
            let d = usize::from((v >> shift) & 0xF);
            self.str(DIGITS.get(d..=d).unwrap_or("?"))?;
        }
        Ok(())
    }
}

impl Text for fmt::Formatter<'_> {
    fn str(&mut self, s: &str) -> fmt::Result {
        self.write_str(s)
    }
    fn lit(&mut self, s: &'static str, _: Interned) -> fmt::Result {
        self.write_str(s)
    }
    fn dec(&mut self, v: u32) -> fmt::Result {
        fmt::Display::fmt(&v, self)
    }
}

/// A defmt formatter as a [`Text`] sink: each piece is one `defmt::write!`, and the host
/// renders them back to back.
#[cfg(feature = "defmt")]
pub(crate) struct Defmt<'a>(pub(crate) defmt::Formatter<'a>);

#[cfg(feature = "defmt")]
impl Text for Defmt<'_> {
    fn str(&mut self, s: &str) -> fmt::Result {
        defmt::write!(self.0, "{=str}", s);
        Ok(())
    }
    fn lit(&mut self, _: &'static str, i: Interned) -> fmt::Result {
        defmt::write!(self.0, "{=istr}", i);
        Ok(())
    }
    fn dec(&mut self, v: u32) -> fmt::Result {
        defmt::write!(self.0, "{=u32}", v);
        Ok(())
    }
}
