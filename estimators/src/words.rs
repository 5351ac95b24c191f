//! A bank's parameters as a sequence of 64-bit integer words ([`Words`]): what building a
//! bank computed (`f64` and `libm` on a host), stored as numbers and read back with integer
//! moves only, the way a filter takes its coefficients. A firmware keeps a table of banks
//! built on the host and reads the one it needs ([`Bank::from_words`](crate::Bank::from_words),
//! docs/FOOTPRINT.md).
//!
//! A value's words are its numbers in declaration order: a [`Real`](crate::Real) as its bits
//! (`Fx` its raw Q31.32 bits, `f32` and `f64` their IEEE bits), an integer as itself, an enum
//! as its variant's index. Nothing but the law's parameters is stored: a bank reads back as
//! [`Bank::new`](crate::Bank::new) builds it, before its first sample.
//!
//! The words are not validated again when they are read: read only what
//! [`Words::put_words`] of the same type and crate version wrote (a table built with the
//! image). Other words can give a bank whose parameters `Bank::new` would have refused (a
//! step of 0 us, an unstable gain), and such a bank can panic or diverge.

use crate::{Fx, Hold, KalmanOutput, Wrap};

/// Where a value's words are read from: a source of words (`None` once it is exhausted).
/// Reading past the source's end gives 0 and marks the reader short ([`Self::short`]).
pub struct WordReader<'a> {
    next: &'a mut dyn FnMut() -> Option<i64>,
    short: bool,
}

impl<'a> WordReader<'a> {
    /// A reader of the words `next` yields, in order.
    pub fn new(next: &'a mut dyn FnMut() -> Option<i64>) -> Self {
        Self { next, short: false }
    }

    /// The next word (0 when the source is exhausted).
    pub fn word(&mut self) -> i64 {
        match (self.next)() {
            Some(w) => w,
            None => {
                self.short = true;
                0
            }
        }
    }

    /// True when a read found the source exhausted.
    pub fn short(&self) -> bool {
        self.short
    }

    /// True when every word was read and none is left over (consumes the next word, if any).
    pub fn read_exactly(&mut self) -> bool {
        !self.short && (self.next)().is_none()
    }
}

/// A value stored as 64-bit words: [`Self::put_words`] writes them, [`Self::take_words`] reads
/// them back (see the [module documentation](self)).
pub trait Words: Sized {
    /// Writes the value's words, in order.
    fn put_words(&self, out: &mut dyn FnMut(i64));
    /// Reads a value [`Self::put_words`] wrote.
    fn take_words(r: &mut WordReader<'_>) -> Self;
}

impl Words for u32 {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        out(i64::from(*self));
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        r.word() as u32
    }
}

impl Words for u64 {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        out(*self as i64);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        r.word() as u64
    }
}

impl Words for f32 {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        out(i64::from(self.to_bits()));
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        f32::from_bits(r.word() as u32)
    }
}

impl Words for f64 {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        out(self.to_bits() as i64);
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        f64::from_bits(r.word() as u64)
    }
}

impl Words for Fx {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        out(self.to_bits());
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        Fx::from_bits(r.word())
    }
}

impl<X: Words + Copy, const N: usize> Words for [X; N] {
    fn put_words(&self, out: &mut dyn FnMut(i64)) {
        for x in self {
            x.put_words(out);
        }
    }
    fn take_words(r: &mut WordReader<'_>) -> Self {
        core::array::from_fn(|_| X::take_words(r))
    }
}

/// An enum as its variant's index (`as i64`); an index it does not have reads as its first
/// variant.
macro_rules! enum_words {
    ($t:ty: $first:path $(, $v:path)*) => {
        impl Words for $t {
            fn put_words(&self, out: &mut dyn FnMut(i64)) {
                out(*self as i64);
            }
            fn take_words(r: &mut WordReader<'_>) -> Self {
                let w = r.word();
                $(
                    if w == $v as i64 {
                        return $v;
                    }
                )*
                $first
            }
        }
    };
}

enum_words!(Hold: Hold::Linear, Hold::ZeroOrder);
enum_words!(Wrap: Wrap::Deg180, Wrap::None);
enum_words!(KalmanOutput: KalmanOutput::Velocity, KalmanOutput::Acceleration);

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<X: Words + PartialEq + core::fmt::Debug>(x: X) {
        let mut buf = [0i64; 8];
        let mut n = 0;
        x.put_words(&mut |w| {
            buf[n] = w;
            n += 1;
        });
        let mut it = buf[..n].iter().copied();
        let mut next = || it.next();
        let mut r = WordReader::new(&mut next);
        assert_eq!(X::take_words(&mut r), x);
        assert!(r.read_exactly());
    }

    #[test]
    fn every_kind_of_word_reads_back() {
        round_trip(u32::MAX);
        round_trip(u64::MAX);
        round_trip(-0.0f32);
        round_trip(f32::MIN_POSITIVE);
        round_trip(-1.0e300f64);
        round_trip(Fx::from_bits(i64::MIN));
        round_trip([Fx::from_bits(-3), Fx::from_bits(1 << 40)]);
        round_trip((Hold::ZeroOrder, Wrap::None, KalmanOutput::Acceleration));
        round_trip((Hold::Linear, Wrap::Deg180, KalmanOutput::Velocity));
    }

    #[test]
    fn a_short_or_long_source_is_seen() {
        let mut it = [1i64].into_iter();
        let mut next = || it.next();
        let mut r = WordReader::new(&mut next);
        assert_eq!(<(u32, u32)>::take_words(&mut r), (1, 0));
        assert!(r.short() && !r.read_exactly());
        let mut it = [1i64, 2, 3].into_iter();
        let mut next = || it.next();
        let mut r = WordReader::new(&mut next);
        assert_eq!(<(u32, u32)>::take_words(&mut r), (1, 2));
        assert!(!r.short() && !r.read_exactly());
    }
}
