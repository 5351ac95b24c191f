//! The generator of the packet table: `packet_table!` turns the one declaration per packet
//! (in `table.rs`) into the views, the `*Fields` structs, the [`Packet`](crate::Packet) enum
//! and every dispatch over packet types.
//!
//! Grammar of the table:
//!
//! ```text
//! /// doc of the view
//! View(ViewFields, TYPE, LEN, stream|reply) {
//!     /// doc of the field
//!     name: kind[si_accessor, ...] @ offset => role;
//!     ..group @ offset;
//!     ...
//! }
//! ```
//!
//! `kind` is one of the arms of `kind!` (fields.rs): it fixes the wire type, the scale, the
//! unit and the docs; `[...]` names the SI accessors the kind has (none for time, status,
//! counter and code kinds); `=> role` is optional (see [`Role`](crate::Role)). `stream`
//! marks a type the unit can output continuously (see
//! [`PacketType::output_payload_len`](crate::PacketType::output_payload_len)).
//! `..group @ offset;` stands for the fields of a group several packets share (an arm of
//! `field_group!` in `table.rs`), laid out from `offset` on.

/// One fixed-layout packet: view, `*Fields` struct, layout and role tables.
macro_rules! fixed_packet {
    (
        $(#[$vm:meta])*
        $view:ident($fields:ident, $ptype:ident, $len:literal) {
            $(
                $(#[$fm:meta])*
                $f:ident: $kind:ident $([$($acc:ident),+])? @ $off:expr $(=> $role:ident)?;
            )*
        }
    ) => {
        $(#[$vm])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $view<'a> {
            payload: &'a [u8; $len],
        }

        impl<'a> $view<'a> {
            /// Payload length in bytes.
            pub const LEN: usize = $len;
            /// The packet type.
            pub const TYPE: PacketType = PacketType::$ptype;
            /// The packet's line of the table: every field in payload order.
            pub const FIELDS: &'static [FieldInfo] = &[
                $(
                    FieldInfo {
                        name: stringify!($f),
                        offset: $off,
                        size: core::mem::size_of::<kind!(@ty $kind)>(),
                        kind: kind!(@kind $kind),
                        role: kind!(@role $kind $($role)?),
                    },
                )*
            ];
            /// Where the role fields are.
            pub(crate) const ROLES: Roles = Roles::NONE
                $( .with(kind!(@role $kind $($role)?), kind!(@kind $kind), $off) )*;

            /// Wraps a payload; a length other than [`Self::LEN`] is [`DecodeError::Length`].
            pub fn new(payload: &'a [u8]) -> Result<Self, DecodeError> {
                match <&[u8; $len]>::try_from(payload) {
                    Ok(payload) => Ok(Self { payload }),
                    Err(_) => Err(DecodeError::Length {
                        packet_type: PacketType::$ptype,
                        expected: $len,
                        actual: payload.len(),
                    }),
                }
            }

            /// The raw payload bytes.
            pub fn payload(&self) -> &'a [u8] {
                self.payload
            }

            /// Copies every raw field into the fields struct.
            pub fn fields(&self) -> $fields {
                $fields { $($f: self.$f(),)* }
            }

            $(
                $(#[$fm])*
                ///
                #[doc = kind!(@doc $kind)]
                #[inline]
                pub fn $f(&self) -> kind!(@ty $kind) {
                    <kind!(@ty $kind) as BeField>::read(self.payload, $off)
                }
                kind!(@si $kind, $f, [$($($acc),+)?]);
                kind!(@role_methods $f $($role)?);
            )*

            /// Calls `f` with every field in payload order: its name, its raw wire integer,
            /// its physical value and unit where it has one (see [`Field`] and [`Quantity`]
            /// for the units), whether it is a status word, and its kind. No allocation, no
            /// panic.
            pub fn for_each_field(&self, mut f: impl FnMut(Field)) {
                $(
                    f(Field {
                        name: stringify!($f),
                        raw: i64::from(self.$f()),
                        si: kind!(@quantity $kind, self, $f, [$($($acc),+)?]),
                        flags: kind!(@kind $kind).is_flags(),
                        kind: kind!(@kind $kind),
                    });
                )*
            }
        }

        // The table's offsets tile the payload exactly (no gap, no overlap).
        const _: () = assert!(
            tiles($view::FIELDS, $len),
            concat!("fields of ", stringify!($view), " do not tile its payload")
        );

        #[doc = concat!("Raw fields of a `", stringify!($ptype), "` packet (wire integers; see [`", stringify!($view), "`] for units).")]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub struct $fields {
            $(
                $(#[$fm])*
                ///
                #[doc = kind!(@doc $kind)]
                pub $f: kind!(@ty $kind),
            )*
        }

        impl $fields {
            /// The payload bytes (big-endian fields at their offsets).
            pub fn payload(&self) -> [u8; $len] {
                #[allow(unused_mut)]
                let mut p = [0u8; $len];
                $( BeField::write(self.$f, &mut p, $off); )*
                p
            }

            /// Writes the whole frame (preamble, type, length, payload, CRC) into `out`;
            /// returns its length in bytes.
            pub fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError> {
                encode_frame(PacketType::$ptype, &self.payload(), out)
            }
        }

        impl<'a> From<$view<'a>> for $fields {
            fn from(v: $view<'a>) -> Self {
                v.fields()
            }
        }
    };
}

/// Reads a packet's body line by line, replacing each `..group @ offset;` by the group's
/// fields (`field_group!`), then hands the packet to `fixed_packet!`. Called as
/// `splice_groups! { [packet head] [fields so far] lines to read }`.
macro_rules! splice_groups {
    ([$($head:tt)*] [$($fields:tt)*]) => {
        fixed_packet! { $($head)* { $($fields)* } }
    };
    ([$($head:tt)*] [$($fields:tt)*] ..$group:ident @ $off:literal; $($rest:tt)*) => {
        field_group! { $group @ $off, [$($head)*] [$($fields)*] $($rest)* }
    };
    (
        [$($head:tt)*] [$($fields:tt)*]
        $(#[$fm:meta])*
        $f:ident: $kind:ident $([$($acc:ident),+])? @ $off:expr $(=> $role:ident)?;
        $($rest:tt)*
    ) => {
        splice_groups! {
            [$($head)*]
            [$($fields)* $(#[$fm])* $f: $kind $([$($acc),+])? @ $off $(=> $role)?;]
            $($rest)*
        }
    };
}

/// The end of an arm of `field_group!`: appends the group's fields `$group` to the fields
/// read so far and reads on.
macro_rules! group_fields {
    ([[$($head:tt)*] [$($fields:tt)*] $($rest:tt)*] $($group:tt)*) => {
        splice_groups! { [$($head)*] [$($fields)* $($group)*] $($rest)* }
    };
}

macro_rules! stream_flag {
    (stream) => {
        true
    };
    (reply) => {
        false
    };
}

/// The whole table: every fixed packet, then the [`Packet`](crate::Packet) enum and its
/// dispatch. The variable-length and command packets (ID, PK, CH, GP, AR, SR, SF, WF, GF,
/// RF, unknown types) are written here once, as they do not change with the table.
macro_rules! packet_table {
    (
        $(
            $(#[$vm:meta])*
            $view:ident($fields:ident, $ptype:ident, $len:literal, $stream:ident) {
                $($body:tt)*
            }
        )*
    ) => {
        $(
            splice_groups! {
                [$(#[$vm])* $view($fields, $ptype, $len)] []
                $($body)*
            }
        )*

        /// A decoded frame.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        pub enum Packet<'a> {
            $(
                $(#[$vm])*
                $view($view<'a>),
            )*
            /// ID serial number and model.
            Id(Id<'a>),
            /// PK ping reply (empty payload).
            Ping,
            /// CH echo reply: the echoed bytes.
            Echo(&'a [u8]),
            /// GP (a get-packet request seen on the line): the requested type.
            GetPacket(PacketType),
            /// AR algorithm-reset reply (empty payload).
            AlgorithmReset,
            /// SR software-reset reply (empty payload).
            SoftwareReset,
            /// SF reply: the accepted field IDs.
            SetFields(FieldIds<'a>),
            /// WF reply: the accepted field IDs.
            WriteFields(FieldIds<'a>),
            /// GF reply: (ID, value) pairs from RAM.
            GetFields(FieldValues<'a>),
            /// RF reply: (ID, value) pairs from EEPROM.
            ReadFields(FieldValues<'a>),
            /// Any other type (e.g. OpenIMU lower-case packets), passed through raw.
            Unknown(Frame<'a>),
        }

        /// (type, payload length, streamable) of every fixed-layout packet.
        const FIXED: &[(PacketType, usize, bool)] = &[
            $( (PacketType::$ptype, $len, stream_flag!($stream)), )*
        ];

        impl PacketType {
            /// The packet table's line of a fixed-layout type: every field of its payload in
            /// order, as the view's `FIELDS` ([`A2::FIELDS`](crate::A2::FIELDS), ...); `None`
            /// for the other types (commands, ID, unknown). With
            /// [`encode_frame`](crate::encode_frame) this writes any packet of the table from
            /// its field values, with no code per type.
            pub const fn payload_fields(self) -> Option<&'static [FieldInfo]> {
                let c = self.code();
                $(
                    if c == PacketType::$ptype.code() {
                        return Some($view::FIELDS);
                    }
                )*
                None
            }
        }

        impl<'a> Packet<'a> {
            /// Decodes a CRC-checked frame (unit -> host direction: SF/WF/GF/RF are replies).
            /// A known type with the wrong payload length is a [`DecodeError`].
            pub fn decode(frame: Frame<'a>) -> Result<Packet<'a>, DecodeError> {
                let p = frame.payload;
                let t = frame.packet_type;
                Ok(match t {
                    $( PacketType::$ptype => Packet::$view($view::new(p)?), )*
                    PacketType::ID => Packet::Id(Id::new(p)?),
                    PacketType::PK
                    | PacketType::SF
                    | PacketType::WF
                    | PacketType::GF
                    | PacketType::RF => return Self::decode_reply(frame),
                    PacketType::CH => Packet::Echo(p),
                    PacketType::GP => match <[u8; 2]>::try_from(p) {
                        Ok(b) => Packet::GetPacket(PacketType(b)),
                        Err(_) => {
                            return Err(DecodeError::Length {
                                packet_type: t,
                                expected: 2,
                                actual: p.len(),
                            })
                        }
                    },
                    PacketType::AR => {
                        empty(t, p)?;
                        Packet::AlgorithmReset
                    }
                    PacketType::SR => {
                        empty(t, p)?;
                        Packet::SoftwareReset
                    }
                    _ => Packet::Unknown(frame),
                })
            }

            /// [`Packet::decode`] of the replies a host awaits after a command (NAK, PK, SF,
            /// WF, GF, RF): the same packet or error for those types, [`Packet::Unknown`]
            /// (not decoded) for every other. The driver's reply wait links this decoder,
            /// not the whole packet table.
            pub fn decode_reply(frame: Frame<'a>) -> Result<Packet<'a>, DecodeError> {
                let p = frame.payload;
                let t = frame.packet_type;
                Ok(match t {
                    PacketType::NAK => Packet::Nak(Nak::new(p)?),
                    PacketType::PK => {
                        empty(t, p)?;
                        Packet::Ping
                    }
                    PacketType::SF => Packet::SetFields(FieldIds::new(t, p)?),
                    PacketType::WF => Packet::WriteFields(FieldIds::new(t, p)?),
                    PacketType::GF => Packet::GetFields(FieldValues::new(t, p)?),
                    PacketType::RF => Packet::ReadFields(FieldValues::new(t, p)?),
                    _ => Packet::Unknown(frame),
                })
            }

            /// The packet's type.
            pub fn packet_type(&self) -> PacketType {
                match self {
                    $( Packet::$view(_) => PacketType::$ptype, )*
                    Packet::Id(_) => PacketType::ID,
                    Packet::Ping => PacketType::PK,
                    Packet::Echo(_) => PacketType::CH,
                    Packet::GetPacket(_) => PacketType::GP,
                    Packet::AlgorithmReset => PacketType::AR,
                    Packet::SoftwareReset => PacketType::SR,
                    Packet::SetFields(_) => PacketType::SF,
                    Packet::WriteFields(_) => PacketType::WF,
                    Packet::GetFields(_) => PacketType::GF,
                    Packet::ReadFields(_) => PacketType::RF,
                    Packet::Unknown(f) => f.packet_type,
                }
            }

            /// The time stamp of an output packet (`TimeStamp::None` for packets without
            /// one: S1, S2, T0, and every non-output packet).
            #[inline]
            pub fn time(&self) -> TimeStamp {
                match self {
                    $( Packet::$view(v) => $view::ROLES.time(v.payload), )*
                    _ => TimeStamp::None,
                }
            }

            /// The BIT word of an output packet that has one (S0, S1, S2, A0, A1, A2, N0, N1,
            /// B1, T0).
            #[inline]
            pub fn bit(&self) -> Option<Bit> {
                match self {
                    $( Packet::$view(v) => $view::ROLES.bit(v.payload), )*
                    _ => None,
                }
            }

            /// Roll, pitch and yaw (deg) of a packet that carries all three (A0, A1, A2, N0,
            /// N1, B1); `None` for any other packet. Generated from the table's `roll`,
            /// `pitch` and `yaw` roles: a new packet type with these roles is covered with
            /// no other change. Same values as the views' `*_deg` accessors (`roll_deg`,
            /// `pitch_deg`, `yaw_true_deg` / `yaw_mag_deg` / `yaw_deg`).
            ///
            /// With [`Packet::body_rates`], [`Packet::time`] and [`Packet::bit`] this is what a
            /// three-axis pipeline reads from any packet.
            ///
            /// ```
            /// use nav440_proto::{A2Fields, Frame, Packet, PacketType};
            ///
            /// // roll 10 deg (0x071C), pitch -5 deg, yaw 90 deg; rates 1, 2, 3 deg/s.
            /// let a2 = A2Fields {
            ///     roll: 0x071C, pitch: -0x038E, yaw_true: 0x4000,
            ///     rate_x: 0x34, rate_y: 0x68, rate_z: 0x9C, bit: 0x0002,
            ///     ..Default::default()
            /// };
            /// let payload = a2.payload();
            /// let p = Packet::decode(Frame { packet_type: PacketType::A2, payload: &payload }).unwrap();
            /// let att = p.attitude().unwrap();
            /// assert!((att.roll_deg - 10.0).abs() < 0.003 && (att.pitch_deg + 5.0).abs() < 0.003);
            /// assert_eq!(att.yaw_deg, 90.0);
            /// let w = p.body_rates().unwrap();
            /// assert!((w.p_deg_s - 1.0).abs() < 0.01 && (w.r_deg_s - 3.0).abs() < 0.01);
            /// let bit = p.bit().unwrap();
            /// assert!(bit.hardware_error() && !bit.is_fatal());
            /// ```
            #[inline]
            pub fn attitude(&self) -> Option<Attitude> {
                match self {
                    $( Packet::$view(v) => $view::ROLES.attitude(v.payload), )*
                    _ => None,
                }
            }

            /// Body rates p, q, r (deg/s) of a packet that carries all three (S0, S1, A0, A1,
            /// A2, N0, N1; B1 has only r: `None`); generated from the table's `p`, `q`, `r`
            /// roles. Same values as the views' `rate_x_deg_s`, `rate_y_deg_s`,
            /// `rate_z_deg_s`.
            #[inline]
            pub fn body_rates(&self) -> Option<BodyRates> {
                match self {
                    $( Packet::$view(v) => $view::ROLES.body_rates(v.payload), )*
                    _ => None,
                }
            }

            /// Calls `f` with every field of a fixed-layout packet (S0, S1, S2, A0, A1, A2,
            /// N0, N1, B1, T0, VR, NAK) in payload order: name, raw wire integer, physical
            /// value and [`Unit`] (rad, rad/s, g, gauss, degC, m/s, m, ms; see [`Quantity`]),
            /// whether it is a status word, and its [`Kind`]. Packets without a fixed layout
            /// (ID, PK, CH, GP, AR, SR, SF, WF, GF, RF and unknown types) have no such fields:
            /// `f` is not called. No allocation, no panic.
            ///
            /// ```
            /// use nav440_proto::{A2Fields, Frame, Packet, PacketType, SiValue, Unit};
            ///
            /// let payload = A2Fields { roll: 0x071C, time_itow: 123_456, ..Default::default() }.payload();
            /// let p = Packet::decode(Frame { packet_type: PacketType::A2, payload: &payload }).unwrap();
            /// let mut roll = None;
            /// p.for_each_field(|f| {
            ///     if f.name == "roll" {
            ///         roll = f.si.map(|q| (f.raw, q.value.to_f64(), q.unit));
            ///     }
            /// });
            /// let (raw, rad, unit) = roll.unwrap();
            /// assert_eq!((raw, unit), (0x071C, Unit::Rad));
            /// assert_eq!(unit.to_string(), "rad");
            /// assert!((rad - 10f64.to_radians()).abs() < 1e-4);
            /// ```
            pub fn for_each_field(&self, f: impl FnMut(Field)) {
                match self {
                    $( Packet::$view(v) => v.for_each_field(f), )*
                    _ => {}
                }
            }

            /// Time, yaw and body z rate of packets that carry yaw and r (A0, A1, A2, N0, N1,
            /// B1); generated from the table's `yaw`, `r` and `time` roles.
            #[inline]
            pub fn yaw_sample(&self) -> Option<YawSample> {
                match self {
                    $( Packet::$view(v) => $view::ROLES.yaw_sample(v.payload), )*
                    _ => None,
                }
            }
        }
    };
}
