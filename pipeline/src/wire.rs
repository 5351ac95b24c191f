//! The rows as framed binary messages (feature `wire`): what the firmware's `uart-rows` image
//! sends out of a second UART and `nav440 rows` turns back into the CSV of `nav440 estimate`.
//!
//! **Wire format, version [`VERSION`]** (docs/UART-ROWS.md). A stream is a sequence of frames,
//! each one [`Message`] encoded with [postcard](https://docs.rs/postcard) (serde; integers as
//! varints, `f32`/`f64` as their IEEE 754 little-endian bytes, `Option` as a 0/1 tag, sequences
//! with a varint length), then COBS-encoded and ended by the delimiter byte 0x00 ([`DELIMITER`],
//! which occurs nowhere else). The sender starts the stream with a lone delimiter, then a
//! [`Header`] frame, then one [`RowFrame`] per row (the header may be repeated; every copy is
//! the same). A receiver that starts anywhere drops the bytes up to the first delimiter and
//! reads from there ([`Deframer`]).
//!
//! * [`Header`]: the format version ([`VERSION`]), the estimated axes as a mask (roll = 1,
//!   pitch = 2, yaw = 4) and the bank's channel names joined with `,` (its CSV columns, e.g.
//!   `ilo1_v,kf_a`), preceded by `body_rate,` when the rows carry the unit's body rates
//!   instead of the Euler reference rates ([`crate::RateColumn::header_names`]; a pipeline
//!   with [`crate::BodyRates`]).
//! * [`RowFrame`]: the sample time (us since the first sample) and one entry per estimated axis
//!   in the order roll, pitch, yaw: `None` when the row has no estimate for the axis (near
//!   gimbal lock), else an [`AxisFrame`]: the unwrapped angle (deg, f32), its f64 residual (deg),
//!   the rate column (deg/s, `None` when absent: the Euler reference rate, or the body rate
//!   when the header says so) and the bank's channel values (f32: deg/s, deg/s^2).
//!
//! The values are the exact bits the pipeline computed, so [`Layout::write_row`] (through
//! [`crate::csv::write_row`]) prints the text `nav440 estimate` prints.
//!
//! ```
//! use nav440_pipeline::wire::{self, Deframer, Header, Layout, Message};
//! use nav440_pipeline::{Axes, Axis};
//! use estimators::{EstimatorOutput, ProductOutput};
//!
//! // The sender: a delimiter, the header frame, then the rows.
//! let columns = <ProductOutput>::CSV_COLUMNS.to_string();
//! let header = Message::Header(Header::new(Axes::only(Axis::Yaw), &columns));
//! let mut stream = vec![wire::DELIMITER];
//! let mut buf = [0u8; 256];
//! stream.extend_from_slice(wire::encode(&header, &mut buf).unwrap());
//!
//! // The receiver: frames back, the header line of `nav440 estimate --bank product`.
//! let mut deframer = Deframer::<512>::new();
//! let mut csv = String::new();
//! deframer.feed(&stream, |m| {
//!     if let Ok(Message::Header(h)) = m {
//!         Layout::from_header(&h).unwrap().write_header(&mut csv).unwrap();
//!     }
//! });
//! assert_eq!(csv, "t,yaw,yaw_rate,ilo1_v,kf_a");
//! assert_eq!(deframer.counters().frames, 1);
//! ```

use crate::{csv, Axes, Axis, AxisRow, RateColumn, Row};
use core::fmt::{self, Write};
use estimators::{BankOutput, ChannelLists, EstimatorOutput, PaperOutput, ProductOutput};
use serde::{Deserialize, Serialize};

/// The version of the format this crate writes and reads (the [`Header`]'s first field).
pub const VERSION: u8 = 1;

/// The frame delimiter (COBS leaves no other 0x00 in a frame).
pub const DELIMITER: u8 = 0;

/// The most channel values an [`AxisFrame`] holds: the paper bank's 14.
pub const MAX_CHANNELS: usize = 14;

const _: () = assert!(<PaperOutput>::CHANNELS <= MAX_CHANNELS);
const _: () = assert!(<ProductOutput>::CHANNELS <= MAX_CHANNELS);

/// One frame's content.
// No heap to box the row into; a message lives on the stack for one frame.
#[allow(clippy::large_enum_variant)]
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub enum Message<'a> {
    /// What the rows hold (variant 0: its first encoded bytes are `0x00`, then the version).
    #[serde(borrow)]
    Header(Header<'a>),
    /// One row.
    Row(RowFrame),
}

/// The header frame: the format version, the axes, the bank's columns.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header<'a> {
    /// [`VERSION`] (a receiver refuses another).
    pub version: u8,
    /// The estimated axes, a bit mask: roll = 1, pitch = 2, yaw = 4 ([`axes_mask`]).
    pub axes: u8,
    /// The bank's channel names joined with `,` (`EstimatorOutput::CSV_COLUMNS`), preceded
    /// by `body_rate,` for rows with the body rates ([`RateColumn::header_names`]).
    pub columns: &'a str,
}

impl<'a> Header<'a> {
    /// The header of this version for the rows of `axes` of a bank whose columns are
    /// `columns`.
    pub fn new(axes: Axes, columns: &'a str) -> Self {
        Header {
            version: VERSION,
            axes: axes_mask(axes),
            columns,
        }
    }
}

/// One row: the time and one entry per estimated axis (roll, pitch, yaw order).
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct RowFrame {
    /// Sample time, us since the first sample.
    pub t_us: u64,
    /// Per estimated axis: `None` when the row has no estimate for it (near gimbal lock).
    pub axes: heapless::Vec<Option<AxisFrame>, 3>,
}

/// One axis of a row.
#[derive(Serialize, Deserialize, Clone, Debug, PartialEq)]
pub struct AxisFrame {
    /// The unwrapped angle rounded to f32, deg.
    pub angle_deg: f32,
    /// What f32 rounding took off the angle, deg (0 while f32 holds it).
    pub residual_deg: f64,
    /// The rate column, deg/s (`None` when there is none): the Euler-kinematics reference
    /// rate, or the body rate about the axis when the header names `body_rate`.
    pub reference_deg_s: Option<f32>,
    /// The bank's channel values in its channel order (deg/s, deg/s^2).
    pub values: heapless::Vec<f32, MAX_CHANNELS>,
}

impl AxisFrame {
    /// The frame of one axis of a pipeline row.
    pub fn from_axis<O: EstimatorOutput>(a: &AxisRow<O>) -> Self {
        // A bank has at most MAX_CHANNELS channels (checked above for the banks the receiver
        // knows; another bank's extra values are cut and the receiver refuses its columns).
        let values = a.out.values().take(MAX_CHANNELS).collect();
        AxisFrame {
            angle_deg: a.out.unwrapped_deg(),
            residual_deg: a.out.residual_deg(),
            reference_deg_s: a.reference_deg_s,
            values,
        }
    }
}

impl RowFrame {
    /// The frame of a pipeline row whose estimated axes are `axes`.
    pub fn from_row<O: EstimatorOutput>(row: &Row<O>, axes: Axes) -> Self {
        let mut out = heapless::Vec::new();
        for axis in axes.iter() {
            // Cannot fail: at most 3 axes.
            let _ = out.push(row.axis(axis).map(AxisFrame::from_axis));
        }
        RowFrame {
            t_us: row.t_us,
            axes: out,
        }
    }
}

/// The bit mask of `axes`: roll = 1, pitch = 2, yaw = 4.
pub fn axes_mask(axes: Axes) -> u8 {
    axes.iter().fold(0, |m, a| m | 1 << a.index())
}

/// The axes of a mask ([`axes_mask`]); bits above 4 are ignored.
pub fn mask_axes(mask: u8) -> Axes {
    Axis::ALL
        .iter()
        .filter(|a| mask & (1 << a.index()) != 0)
        .fold(Axes::NONE, |axes, a| axes.with(*a))
}

/// Encodes `message` into `buf` as one frame (postcard, COBS, the trailing [`DELIMITER`]);
/// the frame's bytes. Fails when `buf` is too small ([`max_row_frame_bytes`]).
pub fn encode<'b>(
    message: &Message<'_>,
    buf: &'b mut [u8],
) -> Result<&'b mut [u8], postcard::Error> {
    postcard::to_slice_cobs(message, buf)
}

/// The most bytes a row frame of `axes` axes with `channels` values each takes, delimiter
/// included: the message (variant 1, the time as a varint of at most 10 bytes, the axes'
/// count, per axis 1 + 4 + 8 + 5 + 1 + 4 x `channels`), COBS's overhead (1 per 254 bytes,
/// rounded up) and the delimiter.
pub const fn max_row_frame_bytes(axes: usize, channels: usize) -> usize {
    let message = 1 + 10 + 1 + axes * (1 + 4 + 8 + 5 + 1 + 4 * channels);
    message + message.div_ceil(254) + 1
}

/// Why a frame was not read.
#[derive(Clone, Debug, PartialEq)]
pub enum FrameError {
    /// The frame is longer than the receiver's buffer (`bytes`, delimiter excluded): dropped
    /// up to the next delimiter.
    TooLong {
        /// The frame's length, bytes.
        bytes: usize,
    },
    /// Not valid COBS (a corrupted or cut frame).
    Cobs {
        /// The frame's length, bytes.
        bytes: usize,
    },
    /// Valid COBS, but not a message of this format (corrupted, or cut and joined).
    Decode {
        /// The frame's length, bytes.
        bytes: usize,
        /// What postcard said.
        error: postcard::Error,
    },
    /// A header of another format version.
    Version {
        /// The version in the header.
        found: u8,
    },
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::TooLong { bytes } => {
                write!(f, "frame of {bytes} bytes is longer than any message")
            }
            FrameError::Cobs { bytes } => write!(f, "frame of {bytes} bytes is not valid COBS"),
            FrameError::Decode { bytes, error } => {
                write!(f, "frame of {bytes} bytes is not a row message ({error})")
            }
            FrameError::Version { found } => write!(
                f,
                "header of format version {found}; this reader reads version {VERSION}"
            ),
        }
    }
}

/// What a [`Deframer`] has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeframeCounters {
    /// Bytes fed.
    pub bytes: u64,
    /// Bytes before the first delimiter (a stream joined mid-frame), dropped.
    pub skipped_bytes: u64,
    /// Frames decoded into a [`Message`].
    pub frames: u64,
    /// Frames not decoded ([`FrameError`]).
    pub bad_frames: u64,
}

/// Where a [`Deframer`] is in the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Before the first delimiter: the bytes may be a frame's tail.
    Hunting,
    /// Inside a frame (or between frames).
    Collecting,
    /// Inside a frame too long for the buffer, until the next delimiter.
    Discarding,
}

/// Splits a byte stream into frames at [`DELIMITER`] and decodes each ([`Message`]); `N` is
/// its buffer, the longest frame it reads (a frame of [`max_row_frame_bytes`] fits in 512).
/// No heap; any input, also garbage, gives messages or [`FrameError`]s, never a panic.
pub struct Deframer<const N: usize> {
    buf: [u8; N],
    len: usize,
    state: State,
    counters: DeframeCounters,
}

impl<const N: usize> Default for Deframer<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Deframer<N> {
    /// A deframer at the start of a stream, before its first delimiter.
    pub const fn new() -> Self {
        Deframer {
            buf: [0; N],
            len: 0,
            state: State::Hunting,
            counters: DeframeCounters {
                bytes: 0,
                skipped_bytes: 0,
                frames: 0,
                bad_frames: 0,
            },
        }
    }

    /// What it has seen so far.
    pub fn counters(&self) -> DeframeCounters {
        self.counters
    }

    /// Bytes of an unfinished frame held (no delimiter after them yet).
    pub fn pending_bytes(&self) -> usize {
        match self.state {
            State::Collecting => self.len,
            _ => 0,
        }
    }

    /// Feeds bytes in any chunks; `on_frame` gets each frame they complete, decoded or with
    /// the reason it was not. Empty frames (two delimiters in a row) are skipped.
    pub fn feed(
        &mut self,
        bytes: &[u8],
        mut on_frame: impl FnMut(Result<Message<'_>, FrameError>),
    ) {
        self.counters.bytes += bytes.len() as u64;
        let mut rest = bytes;
        while !rest.is_empty() {
            let end = rest.iter().position(|&b| b == DELIMITER);
            let (part, delimited) = match end {
                Some(i) => (&rest[..i], true),
                None => (rest, false),
            };
            rest = match end {
                Some(i) => &rest[i + 1..],
                None => &[],
            };
            match self.state {
                State::Hunting => {
                    self.counters.skipped_bytes += part.len() as u64;
                    if delimited {
                        self.state = State::Collecting;
                    }
                }
                State::Discarding => {
                    self.len += part.len();
                    if delimited {
                        self.counters.bad_frames += 1;
                        on_frame(Err(FrameError::TooLong { bytes: self.len }));
                        self.len = 0;
                        self.state = State::Collecting;
                    }
                }
                State::Collecting => {
                    if self.len + part.len() > N {
                        self.len += part.len();
                        self.state = State::Discarding;
                        if delimited {
                            self.counters.bad_frames += 1;
                            on_frame(Err(FrameError::TooLong { bytes: self.len }));
                            self.len = 0;
                            self.state = State::Collecting;
                        }
                        continue;
                    }
                    self.buf[self.len..self.len + part.len()].copy_from_slice(part);
                    self.len += part.len();
                    if delimited {
                        let len = core::mem::take(&mut self.len);
                        if len > 0 {
                            let r = decode_frame(&mut self.buf[..len]);
                            match r {
                                Ok(_) => self.counters.frames += 1,
                                Err(_) => self.counters.bad_frames += 1,
                            }
                            on_frame(r);
                        }
                    }
                }
            }
        }
    }
}

/// Decodes one frame's bytes (delimiter excluded) in place.
fn decode_frame(frame: &mut [u8]) -> Result<Message<'_>, FrameError> {
    let bytes = frame.len();
    let n = cobs::decode_in_place(frame).map_err(|_| FrameError::Cobs { bytes })?;
    let raw = &frame[..n];
    match postcard::from_bytes(raw) {
        Ok(Message::Header(h)) if h.version != VERSION => {
            Err(FrameError::Version { found: h.version })
        }
        Ok(m) => Ok(m),
        // A header of a later version whose fields this version cannot read: every version's
        // header starts with its variant (0) and the version byte.
        Err(_) if matches!(raw, [0, v, ..] if *v > VERSION) => {
            Err(FrameError::Version { found: raw[1] })
        }
        Err(error) => Err(FrameError::Decode { bytes, error }),
    }
}

/// The banks a receiver knows, by their channel names (the header's columns).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BankKind {
    /// The paper bank (also the noise-adaptive bank's output): [`PaperOutput`].
    Paper,
    /// The product bank: [`ProductOutput`].
    Product,
}

impl BankKind {
    /// The bank whose columns are `columns`.
    pub fn from_columns(columns: &str) -> Option<Self> {
        if columns == <PaperOutput>::CSV_COLUMNS {
            Some(Self::Paper)
        } else if columns == <ProductOutput>::CSV_COLUMNS {
            Some(Self::Product)
        } else {
            None
        }
    }

    /// Its number of channels.
    pub fn channels(self) -> usize {
        match self {
            Self::Paper => <PaperOutput>::CHANNELS,
            Self::Product => <ProductOutput>::CHANNELS,
        }
    }
}

/// A header the receiver cannot use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayoutError {
    /// Another format version.
    Version(u8),
    /// No axis in the mask.
    NoAxis,
    /// Columns of a bank this crate does not know.
    UnknownBank,
}

impl fmt::Display for LayoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LayoutError::Version(v) => write!(
                f,
                "header of format version {v}; this reader reads version {VERSION}"
            ),
            LayoutError::NoAxis => f.write_str("header names no axis"),
            LayoutError::UnknownBank => {
                f.write_str("header names a bank this reader does not know")
            }
        }
    }
}

/// A row that does not fit the header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowError {
    /// Another number of axes than the header's.
    Axes {
        /// The header's.
        expected: usize,
        /// The row's.
        got: usize,
    },
    /// Another number of channel values than the bank's.
    Channels {
        /// The bank's.
        expected: usize,
        /// The row's.
        got: usize,
    },
    /// The writer failed.
    Write,
}

impl fmt::Display for RowError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RowError::Axes { expected, got } => {
                write!(f, "row with {got} axes, the header says {expected}")
            }
            RowError::Channels { expected, got } => {
                write!(f, "row with {got} channel values, the bank has {expected}")
            }
            RowError::Write => f.write_str("cannot write the row"),
        }
    }
}

/// The rows' axes, bank and rate column, from a header: writes the CSV of the rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// The estimated axes.
    pub axes: Axes,
    /// The bank.
    pub bank: BankKind,
    /// The rate column after each angle (`<axis>_rate` or `<axis>_body_rate`).
    pub rate: RateColumn,
}

impl Layout {
    /// The layout a header describes.
    pub fn from_header(h: &Header<'_>) -> Result<Self, LayoutError> {
        if h.version != VERSION {
            return Err(LayoutError::Version(h.version));
        }
        Self::from_parts(h.axes, h.columns)
    }

    /// The layout of the axes `mask` ([`mask_axes`]) and the columns `columns` (the bank's
    /// channel names, after `body_rate,` for rows with the body rates:
    /// [`RateColumn::split_header`]).
    pub fn from_parts(mask: u8, columns: &str) -> Result<Self, LayoutError> {
        let axes = mask_axes(mask);
        if axes.is_empty() {
            return Err(LayoutError::NoAxis);
        }
        let (rate, channels) = RateColumn::split_header(columns);
        let bank = BankKind::from_columns(channels).ok_or(LayoutError::UnknownBank)?;
        Ok(Layout { axes, bank, rate })
    }

    /// Writes the CSV header line (without line terminator): `nav440 estimate`'s for these
    /// axes, bank and rate column ([`csv::write_header_for`]; `--no-reference` for
    /// [`RateColumn::Body`]).
    pub fn write_header(&self, w: &mut impl Write) -> fmt::Result {
        match self.bank {
            BankKind::Paper => csv::write_header_for::<PaperOutput>(w, self.axes, self.rate),
            BankKind::Product => csv::write_header_for::<ProductOutput>(w, self.axes, self.rate),
        }
    }

    /// Writes `row` as a CSV line (without line terminator), the text [`csv::write_row`]
    /// writes for the pipeline's row of the same values.
    pub fn write_row(&self, w: &mut impl Write, row: &RowFrame) -> Result<(), RowError> {
        match self.bank {
            BankKind::Paper => self.write_as::<PaperOutput>(w, row),
            BankKind::Product => self.write_as::<ProductOutput>(w, row),
        }
    }

    fn write_as<O: FromValues>(&self, w: &mut impl Write, f: &RowFrame) -> Result<(), RowError> {
        let row = self.row::<O>(f)?;
        csv::write_row(w, &row, self.axes).map_err(|_| RowError::Write)
    }

    /// The pipeline row of `f`'s values, for the bank output `O`.
    fn row<O: FromValues>(&self, f: &RowFrame) -> Result<Row<O>, RowError> {
        if f.axes.len() != self.axes.len() {
            return Err(RowError::Axes {
                expected: self.axes.len(),
                got: f.axes.len(),
            });
        }
        let mut row = Row {
            t_us: f.t_us,
            axes: [None; 3],
        };
        for (axis, a) in self.axes.iter().zip(f.axes.iter()) {
            let Some(a) = a else { continue };
            if a.values.len() != O::CHANNELS {
                return Err(RowError::Channels {
                    expected: O::CHANNELS,
                    got: a.values.len(),
                });
            }
            row.axes[axis.index()] = Some(AxisRow {
                reference_deg_s: a.reference_deg_s,
                out: O::from_values(a.angle_deg, a.residual_deg, &a.values),
            });
        }
        Ok(row)
    }
}

/// A bank output rebuilt from its values.
trait FromValues: EstimatorOutput {
    /// The output with the angle `angle` + `residual` (deg) and the channel values `values`
    /// (exactly `CHANNELS` of them).
    fn from_values(angle: f32, residual: f64, values: &[f32]) -> Self;
}

impl<R: ChannelLists, const N: usize> FromValues for BankOutput<R, N> {
    fn from_values(angle: f32, residual: f64, values: &[f32]) -> Self {
        let mut v = [0.0; N];
        v.copy_from_slice(values);
        Self::new(angle, residual, v)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use std::string::String;
    use std::vec::Vec;

    fn axis(angle: f32, reference: Option<f32>, values: &[f32]) -> AxisFrame {
        AxisFrame {
            angle_deg: angle,
            residual_deg: 0.0,
            reference_deg_s: reference,
            values: heapless::Vec::from_slice(values).unwrap(),
        }
    }

    /// A stream: a delimiter, the header, the rows.
    fn stream(header: &Header<'_>, rows: &[RowFrame]) -> Vec<u8> {
        let mut out = std::vec![DELIMITER];
        let mut buf = [0u8; 512];
        out.extend_from_slice(encode(&Message::Header(*header), &mut buf).unwrap());
        for r in rows {
            out.extend_from_slice(encode(&Message::Row(r.clone()), &mut buf).unwrap());
        }
        out
    }

    /// Every frame of `bytes` fed in chunks of `chunk`: the messages (owned) and the errors.
    fn read(bytes: &[u8], chunk: usize) -> (Vec<Result<String, FrameError>>, DeframeCounters) {
        let mut d = Deframer::<512>::new();
        let mut got = Vec::new();
        for c in bytes.chunks(chunk.max(1)) {
            d.feed(c, |m| got.push(m.map(|m| std::format!("{m:?}"))));
        }
        (got, d.counters())
    }

    fn product_rows() -> Vec<RowFrame> {
        (0..5u64)
            .map(|k| {
                let mut axes = heapless::Vec::new();
                axes.push(Some(axis(1.5 * k as f32, Some(-0.75), &[1e-5, 3.0])))
                    .unwrap();
                axes.push(None).unwrap();
                axes.push(Some(axis(170.0, None, &[f32::MIN_POSITIVE, -0.0])))
                    .unwrap();
                RowFrame {
                    t_us: 10_000 * k + 49,
                    axes,
                }
            })
            .collect()
    }

    /// Encode, decode, CSV: the values come back bit for bit, in any chunking, and the CSV is
    /// the pipeline's text for the same row (`csv::write_row`).
    #[test]
    fn round_trip_and_csv() {
        let cols = std::format!("{}", <ProductOutput>::CSV_COLUMNS);
        let header = Header::new(Axes::ALL, &cols);
        assert_eq!(header.axes, 7);
        let rows = product_rows();
        let bytes = stream(&header, &rows);
        for chunk in [1, 3, 64, bytes.len()] {
            let (got, c) = read(&bytes, chunk);
            assert_eq!(c.frames, 6, "chunk {chunk}");
            assert_eq!((c.bad_frames, c.skipped_bytes), (0, 0));
            assert_eq!(got[0], Ok(std::format!("{:?}", Message::Header(header))));
            for (g, r) in got[1..].iter().zip(&rows) {
                assert_eq!(*g, Ok(std::format!("{:?}", Message::Row(r.clone()))));
            }
        }
        // Bit for bit: -0.0 and a subnormal survive.
        let mut d = Deframer::<512>::new();
        let mut back = Vec::new();
        d.feed(&bytes, |m| {
            if let Ok(Message::Row(r)) = m {
                back.push(r);
            }
        });
        assert_eq!(back, rows);
        let bits = |r: &RowFrame| r.axes[2].as_ref().unwrap().values[1].to_bits();
        assert_eq!(bits(&back[0]), (-0.0f32).to_bits());
        // The CSV: the pipeline's text for the row.
        let layout = Layout::from_header(&header).unwrap();
        let mut text = String::new();
        layout.write_header(&mut text).unwrap();
        assert_eq!(
            text,
            "t,roll,roll_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_rate,yaw_ilo1_v,yaw_kf_a"
        );
        text.clear();
        layout.write_row(&mut text, &back[1]).unwrap();
        assert!(
            text.starts_with("0.0100,1.5,-0.75,0.00001,3,,,,,170,,0.0000"),
            "{text}"
        );
        assert!(text.ends_with(",-0"), "{text}");
        let mut pipeline_row: Row<ProductOutput> = Row {
            t_us: 10_049,
            axes: [None; 3],
        };
        pipeline_row.axes[0] = Some(AxisRow {
            reference_deg_s: Some(-0.75),
            out: <ProductOutput>::new(1.5, 0.0, [1e-5, 3.0]),
        });
        pipeline_row.axes[2] = Some(AxisRow {
            reference_deg_s: None,
            out: <ProductOutput>::new(170.0, 0.0, [f32::MIN_POSITIVE, -0.0]),
        });
        let mut expected = String::new();
        csv::write_row(&mut expected, &pipeline_row, layout.axes).unwrap();
        assert_eq!(text, expected);
        // And back from a pipeline row.
        assert_eq!(RowFrame::from_row(&pipeline_row, layout.axes), back[1]);
    }

    /// A stream joined mid-frame, garbage, a corrupted frame, an over-long frame: the bytes
    /// before the first delimiter are skipped, every bad frame is counted and reported, and the
    /// frames after each are read.
    #[test]
    fn resync_after_garbage() {
        let cols = std::format!("{}", <ProductOutput>::CSV_COLUMNS);
        let header = Header::new(Axes::ALL, &cols);
        let mut rows = product_rows();
        for r in &mut rows {
            r.axes[1] = Some(axis(-2.0, Some(0.5), &[0.25, 8.0]));
        }
        let clean = stream(&header, &rows);
        // Joined in the middle of the header frame: the header is lost, the rows are read.
        let (got, c) = read(&clean[5..], 7);
        assert_eq!((c.frames, c.bad_frames), (5, 0));
        assert_eq!(
            c.skipped_bytes as usize,
            clean[5..].iter().position(|&b| b == 0).unwrap()
        );
        assert!(got.iter().all(Result::is_ok));
        // Garbage between frames, a frame with a flipped byte, 600 non-zero bytes.
        let mut bad = clean.clone();
        bad.extend_from_slice(&[0x55, 2, 0x11, 0, 0, 0xFF, 0x10, 0]);
        let mut buf = [0u8; 512];
        let mut flipped = encode(&Message::Row(rows[0].clone()), &mut buf)
            .unwrap()
            .to_vec();
        // The COBS code byte: the frame no longer decodes.
        flipped[0] = 0xFE;
        bad.extend_from_slice(&flipped);
        bad.extend(core::iter::repeat_n(0x55, 600));
        bad.push(0);
        bad.extend_from_slice(encode(&Message::Row(rows[4].clone()), &mut buf).unwrap());
        for chunk in [1, 5, 4096] {
            let (got, c) = read(&bad, chunk);
            assert_eq!(c.frames, 7, "chunk {chunk}: header, 5 rows, the last row");
            assert_eq!(c.bad_frames, 4, "{got:?}");
            assert!(got.contains(&Err(FrameError::TooLong { bytes: 600 })));
            assert_eq!(
                got.last(),
                Some(&Ok(std::format!("{:?}", Message::Row(rows[4].clone()))))
            );
        }
        // A header of another version is said as such.
        let mut other = std::vec![0u8];
        let mut h = header;
        h.version = 2;
        other.extend_from_slice(encode(&Message::Header(h), &mut buf).unwrap());
        let (got, _) = read(&other, 64);
        assert_eq!(got, [Err(FrameError::Version { found: 2 })]);
        assert_eq!(Layout::from_header(&h), Err(LayoutError::Version(2)));
        // Every byte value, every chunking: no panic.
        let noise: Vec<u8> = (0..4000u32)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect();
        for chunk in [1, 2, 17, 4000] {
            let (_, c) = read(&noise, chunk);
            assert_eq!(c.bytes, 4000);
        }
    }

    /// A header whose columns start with `body_rate`: the rows' rate column is the body rate,
    /// the CSV header names it `<axis>_body_rate`, the rows are written alike.
    #[test]
    fn body_rate_header() {
        let cols = std::format!("body_rate,{}", <ProductOutput>::CSV_COLUMNS);
        let header = Header::new(Axes::ALL, &cols);
        let (got, _) = read(&stream(&header, &[]), 64);
        assert_eq!(got, [Ok(std::format!("{:?}", Message::Header(header)))]);
        let layout = Layout::from_header(&header).unwrap();
        assert_eq!(
            (layout.bank, layout.rate),
            (BankKind::Product, RateColumn::Body)
        );
        let mut text = String::new();
        layout.write_header(&mut text).unwrap();
        assert_eq!(
            text,
            "t,roll,roll_body_rate,roll_ilo1_v,roll_kf_a,pitch,pitch_body_rate,pitch_ilo1_v,pitch_kf_a,yaw,yaw_body_rate,yaw_ilo1_v,yaw_kf_a"
        );
        text.clear();
        let rows = product_rows();
        layout.write_row(&mut text, &rows[1]).unwrap();
        let product = std::format!("{}", <ProductOutput>::CSV_COLUMNS);
        let euler = Layout::from_parts(7, &product).unwrap();
        assert_eq!(euler.rate, RateColumn::Euler);
        let mut same = String::new();
        euler.write_row(&mut same, &rows[1]).unwrap();
        assert_eq!(text, same);
        // Yaw alone, paper bank.
        let paper = std::format!("body_rate,{}", <PaperOutput>::CSV_COLUMNS);
        let mut text = String::new();
        Layout::from_parts(4, &paper)
            .unwrap()
            .write_header(&mut text)
            .unwrap();
        assert_eq!(text, csv::HEADER.replace("yaw_rate", "yaw_body_rate"));
    }

    /// A row that does not fit the header is an error, not a line.
    #[test]
    fn rows_must_fit_the_header() {
        let paper = std::format!("{}", <PaperOutput>::CSV_COLUMNS);
        let layout = Layout::from_parts(4, &paper).unwrap();
        assert_eq!(layout.bank, BankKind::Paper);
        let rows = product_rows();
        let mut s = String::new();
        assert_eq!(
            layout.write_row(&mut s, &rows[0]),
            Err(RowError::Axes {
                expected: 1,
                got: 3
            })
        );
        let mut one = rows[0].clone();
        one.axes.truncate(1);
        assert_eq!(
            layout.write_row(&mut s, &one),
            Err(RowError::Channels {
                expected: 14,
                got: 2
            })
        );
        assert_eq!(Layout::from_parts(0, &paper), Err(LayoutError::NoAxis));
        assert_eq!(
            Layout::from_parts(4, "foo_v"),
            Err(LayoutError::UnknownBank)
        );
        assert_eq!(mask_axes(axes_mask(Axes::ALL)), Axes::ALL);
    }

    /// The frame size bound holds for the largest rows (time u64::MAX, every value NaN with
    /// every byte non-zero, the worst case for COBS).
    #[test]
    fn max_frame_size_holds() {
        let v = [f32::from_bits(0xFFFF_FFFF); MAX_CHANNELS];
        let mut axes = heapless::Vec::new();
        for _ in 0..3 {
            let mut a = axis(f32::from_bits(0xFFFF_FFFF), Some(1.0), &v);
            a.residual_deg = f64::from_bits(u64::MAX);
            axes.push(Some(a)).unwrap();
        }
        let row = Message::Row(RowFrame {
            t_us: u64::MAX,
            axes,
        });
        let mut buf = [0u8; 1024];
        let n = encode(&row, &mut buf).unwrap().len();
        assert!(n <= max_row_frame_bytes(3, MAX_CHANNELS), "{n}");
        assert!(max_row_frame_bytes(3, MAX_CHANNELS) <= 512);
    }
}
