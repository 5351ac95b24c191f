//! The Rust source `nav440 tune --rust` writes for a firmware: each gains value as the
//! expression that builds it ([`literal`]), derived from its `serde` form (the fields of every
//! configuration type the library declares, so that a family added to the paper bank needs
//! nothing here), the `use estimators::{..}` line those expressions need, and the shipped
//! preset's rate tables as `estimators/src/rates.rs` holds them ([`write_rate_tables`]).
//!
//! Every gain is written with `{:?}`, its shortest form that reads back to the same `f32`. A
//! struct or an array is written on one line, unless it holds a struct: then one field or
//! element per line, one level deeper (`BankGains { .. }`, the ILOs' array). An enum's
//! variant is written by its Rust name (`DeltaMode::Leaky { sigma: 0.1 }`, which the gains
//! file spells `leaky`).

use std::fmt::{self, Write};

use estimators::presets::AVE_DEFAULT;
use estimators::{BankGains, IloConfig, RateGains, KF_DEFAULT};
use serde::ser::{self, Impossible, Serialize};

/// A value as its Rust expression will write it: what `serde` says of it.
#[derive(Clone, Debug, PartialEq)]
enum Node {
    /// A number or a boolean, as written.
    Scalar(String),
    /// `Name { field: .., .. }`, or for an enum's variant `Enum::Variant { .. }`.
    Struct {
        path: String,
        types: Vec<&'static str>,
        fields: Vec<(&'static str, Node)>,
        /// A struct, not an enum's variant (what puts its container on several lines).
        plain: bool,
    },
    /// `Enum::Variant`.
    Unit { path: String, ty: &'static str },
    /// `[.., ..]`.
    Seq(Vec<Node>),
}

impl Node {
    /// Whether any child is a plain struct (then `self` takes one line per child).
    fn holds_a_struct(&self) -> bool {
        let children: Vec<&Node> = match self {
            Node::Struct { fields, .. } => fields.iter().map(|(_, n)| n).collect(),
            Node::Seq(items) => items.iter().collect(),
            _ => Vec::new(),
        };
        children
            .iter()
            .any(|c| matches!(c, Node::Struct { plain: true, .. }) || c.holds_a_struct())
    }

    /// The type names the expression of every child uses (`self`'s own not included).
    fn child_types(&self, names: &mut Vec<&'static str>) {
        let children: Vec<&Node> = match self {
            Node::Struct { fields, .. } => fields.iter().map(|(_, n)| n).collect(),
            Node::Seq(items) => items.iter().collect(),
            _ => Vec::new(),
        };
        for c in children {
            match c {
                Node::Struct { types, .. } => names.extend(types),
                Node::Unit { ty, .. } => names.push(ty),
                _ => {}
            }
            c.child_types(names);
        }
    }

    /// Writes the expression; continuation lines start with `indent` plus four spaces per
    /// level of nesting.
    fn write(&self, w: &mut String, indent: &str) -> fmt::Result {
        let deeper = format!("{indent}    ");
        let multi = self.holds_a_struct();
        match self {
            Node::Scalar(s) => w.write_str(s),
            Node::Unit { path, .. } => w.write_str(path),
            Node::Struct { path, fields, .. } => {
                write!(w, "{path} {{")?;
                for (i, (name, value)) in fields.iter().enumerate() {
                    if multi {
                        write!(w, "\n{deeper}{name}: ")?;
                        value.write(w, &deeper)?;
                        w.write_str(",")?;
                    } else {
                        let sep = if i == 0 { " " } else { ", " };
                        write!(w, "{sep}{name}: ")?;
                        value.write(w, indent)?;
                    }
                }
                if multi {
                    write!(w, "\n{indent}}}")
                } else {
                    w.write_str(" }")
                }
            }
            Node::Seq(items) => {
                w.write_str("[")?;
                for (i, value) in items.iter().enumerate() {
                    if multi {
                        write!(w, "\n{deeper}")?;
                        value.write(w, &deeper)?;
                        w.write_str(",")?;
                    } else {
                        if i > 0 {
                            w.write_str(", ")?;
                        }
                        value.write(w, indent)?;
                    }
                }
                if multi {
                    write!(w, "\n{indent}]")
                } else {
                    w.write_str("]")
                }
            }
        }
    }
}

/// A `serde` form that has no Rust literal here (a map, a string, a tuple variant).
#[derive(Debug)]
struct Unsupported(String);

impl fmt::Display for Unsupported {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Unsupported {}

impl ser::Error for Unsupported {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Unsupported(msg.to_string())
    }
}

/// A variant's Rust name from its `serde` name (`leaky` -> `Leaky`, `zero_order` ->
/// `ZeroOrder`; a name already in UpperCamelCase is kept).
fn rust_variant(name: &str) -> String {
    name.split('_')
        .map(|part| {
            let mut c = part.chars();
            c.next()
                .map(|f| f.to_uppercase().chain(c).collect::<String>())
                .unwrap_or_default()
        })
        .collect()
}

/// The `serde` serializer that builds a [`Node`].
struct ToNode;

/// The elements of a sequence or tuple being serialized.
struct SeqNode(Vec<Node>);

/// The fields of a struct or struct variant being serialized.
struct StructNode {
    path: String,
    types: Vec<&'static str>,
    fields: Vec<(&'static str, Node)>,
    plain: bool,
}

impl ser::Serializer for ToNode {
    type Ok = Node;
    type Error = Unsupported;
    type SerializeSeq = SeqNode;
    type SerializeTuple = SeqNode;
    type SerializeTupleStruct = SeqNode;
    type SerializeTupleVariant = Impossible<Node, Unsupported>;
    type SerializeMap = Impossible<Node, Unsupported>;
    type SerializeStruct = StructNode;
    type SerializeStructVariant = StructNode;

    fn serialize_bool(self, v: bool) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_i8(self, v: i8) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_i16(self, v: i16) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_i32(self, v: i32) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_i64(self, v: i64) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_u8(self, v: u8) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_u16(self, v: u16) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_u32(self, v: u32) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_u64(self, v: u64) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(v.to_string()))
    }
    fn serialize_f32(self, v: f32) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(format!("{v:?}")))
    }
    fn serialize_f64(self, v: f64) -> Result<Node, Unsupported> {
        Ok(Node::Scalar(format!("{v:?}")))
    }
    fn serialize_char(self, _: char) -> Result<Node, Unsupported> {
        Err(Unsupported("a char".into()))
    }
    fn serialize_str(self, _: &str) -> Result<Node, Unsupported> {
        Err(Unsupported("a string".into()))
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<Node, Unsupported> {
        Err(Unsupported("bytes".into()))
    }
    fn serialize_none(self) -> Result<Node, Unsupported> {
        Ok(Node::Scalar("None".into()))
    }
    fn serialize_some<T: ?Sized + Serialize>(self, v: &T) -> Result<Node, Unsupported> {
        let mut s = String::from("Some(");
        v.serialize(ToNode)?
            .write(&mut s, "")
            .map_err(|_| Unsupported("an option".into()))?;
        s.push(')');
        Ok(Node::Scalar(s))
    }
    fn serialize_unit(self) -> Result<Node, Unsupported> {
        Ok(Node::Scalar("()".into()))
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<Node, Unsupported> {
        Ok(Node::Unit {
            path: name.into(),
            ty: name,
        })
    }
    fn serialize_unit_variant(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<Node, Unsupported> {
        Ok(Node::Unit {
            path: format!("{name}::{}", rust_variant(variant)),
            ty: name,
        })
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        name: &'static str,
        v: &T,
    ) -> Result<Node, Unsupported> {
        let _ = v;
        Err(Unsupported(format!("the newtype {name}")))
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
        _: &T,
    ) -> Result<Node, Unsupported> {
        Err(Unsupported(format!(
            "the newtype variant {name}::{variant}"
        )))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<SeqNode, Unsupported> {
        Ok(SeqNode(Vec::with_capacity(len.unwrap_or(0))))
    }
    fn serialize_tuple(self, len: usize) -> Result<SeqNode, Unsupported> {
        Ok(SeqNode(Vec::with_capacity(len)))
    }
    fn serialize_tuple_struct(self, name: &'static str, _: usize) -> Result<SeqNode, Unsupported> {
        Err(Unsupported(format!("the tuple struct {name}")))
    }
    fn serialize_tuple_variant(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, Unsupported> {
        Err(Unsupported(format!("the tuple variant {name}::{variant}")))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, Unsupported> {
        Err(Unsupported("a map".into()))
    }
    fn serialize_struct(self, name: &'static str, len: usize) -> Result<StructNode, Unsupported> {
        Ok(StructNode {
            path: name.into(),
            types: vec![name],
            fields: Vec::with_capacity(len),
            plain: true,
        })
    }
    fn serialize_struct_variant(
        self,
        name: &'static str,
        _: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<StructNode, Unsupported> {
        Ok(StructNode {
            path: format!("{name}::{}", rust_variant(variant)),
            types: vec![name],
            fields: Vec::with_capacity(len),
            plain: false,
        })
    }
}

impl ser::SerializeSeq for SeqNode {
    type Ok = Node;
    type Error = Unsupported;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<(), Unsupported> {
        self.0.push(v.serialize(ToNode)?);
        Ok(())
    }
    fn end(self) -> Result<Node, Unsupported> {
        Ok(Node::Seq(self.0))
    }
}

impl ser::SerializeTuple for SeqNode {
    type Ok = Node;
    type Error = Unsupported;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<(), Unsupported> {
        ser::SerializeSeq::serialize_element(self, v)
    }
    fn end(self) -> Result<Node, Unsupported> {
        ser::SerializeSeq::end(self)
    }
}

impl ser::SerializeTupleStruct for SeqNode {
    type Ok = Node;
    type Error = Unsupported;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, v: &T) -> Result<(), Unsupported> {
        ser::SerializeSeq::serialize_element(self, v)
    }
    fn end(self) -> Result<Node, Unsupported> {
        ser::SerializeSeq::end(self)
    }
}

impl ser::SerializeStruct for StructNode {
    type Ok = Node;
    type Error = Unsupported;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), Unsupported> {
        self.fields.push((key, v.serialize(ToNode)?));
        Ok(())
    }
    fn end(self) -> Result<Node, Unsupported> {
        Ok(Node::Struct {
            path: self.path,
            types: self.types,
            fields: self.fields,
            plain: self.plain,
        })
    }
}

impl ser::SerializeStructVariant for StructNode {
    type Ok = Node;
    type Error = Unsupported;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), Unsupported> {
        ser::SerializeStruct::serialize_field(self, key, v)
    }
    fn end(self) -> Result<Node, Unsupported> {
        ser::SerializeStruct::end(self)
    }
}

/// `value` as a Rust expression, each line after the first starting with `indent` (plus its
/// own indentation); empty if its `serde` form has no Rust literal here (a map, a string: no
/// configuration type of the library has one).
pub fn literal<T: Serialize + ?Sized>(value: &T, indent: &str) -> String {
    let mut s = String::new();
    match value.serialize(ToNode) {
        // Writing to a String does not fail.
        Ok(node) => {
            let _ = node.write(&mut s, indent);
        }
        Err(_) => s.clear(),
    }
    s
}

/// A Rust expression `BankGains { .. }` that builds `g` (every field spelled out; gains printed
/// with `{:?}`, which round-trips f32 exactly), each line after the first indented by `indent`.
/// Used by `nav440 tune --rust`.
pub fn bank_gains_literal(g: &BankGains, indent: &str) -> String {
    literal(g, indent)
}

/// `use estimators::{..};` importing `names` and every name a [`BankGains`] literal uses,
/// sorted.
pub fn use_line(names: &[&str]) -> String {
    let mut types = Vec::new();
    if let Ok(node) = BankGains::PAPER_VELOCITY.serialize(ToNode) {
        node.child_types(&mut types);
    }
    let mut all: Vec<&str> = types.into_iter().chain(names.iter().copied()).collect();
    all.sort_unstable();
    all.dedup();
    format!("use estimators::{{{}}};", all.join(", "))
}

/// Writes the tables of `bands` as they stand in `estimators/src/rates.rs` (what
/// `BankConfig::NAV440_RATES` is built from): one per family, one row per band, each gain
/// with `{:?}`, each row labelled with the rates its gains were tuned at. How a re-tuned table
/// is printed (`host-tests/tests/preset_rates.rs`), to paste there.
///
/// An error, and nothing written, when a band cannot be written in the tables: its AVE does
/// not run `AVE_DEFAULT`'s `deltahat` law, or its tracker not `KF_DEFAULT`'s `r`.
pub fn write_rate_tables(bands: &[RateGains], w: &mut dyn Write) -> fmt::Result {
    let writable = |g: &BankGains| g.ave.delta == AVE_DEFAULT.delta && g.kf.r == KF_DEFAULT.r;
    if !bands
        .iter()
        .all(|b| writable(&b.velocity) && writable(&b.acceleration))
    {
        return Err(fmt::Error);
    }
    type Row<'a> = &'a dyn Fn(&mut dyn Write, &RateGains) -> fmt::Result;
    let pairs = |w: &mut dyn Write, v: (f32, f32), a: (f32, f32)| {
        write!(w, "[({:?}, {:?}), ({:?}, {:?})]", v.0, v.1, a.0, a.1)
    };
    let tables: [(&str, &str, &str, Row); 7] = [
        (
            "/// Each band's `(tuned_period_s, below_period_s)`, s (see [`RateGains`]).",
            "PERIODS",
            "([f32; 2], f32)",
            &|w, b| {
                let [lo, hi] = b.tuned_period_s;
                match b.below_period_s {
                    f32::INFINITY => write!(w, "([{lo:?}, {hi:?}], f32::INFINITY)"),
                    below => write!(w, "([{lo:?}, {hi:?}], {below:?})"),
                }
            },
        ),
        (
            "/// AVE `(k, gamma1)`, `[velocity, acceleration]`.",
            "AVE",
            "[(f32, f32); 2]",
            &|w, b| {
                let (v, a) = (b.velocity.ave, b.acceleration.ave);
                pairs(w, (v.k, v.gamma1), (a.k, a.gamma1))
            },
        ),
        (
            "/// ILO1, ILO2, ILO3 `(k1, l, k2)` of the velocity half.",
            "ILO_VELOCITY",
            "[(f32, f32, f32); 3]",
            &|w, b| write_ilo(w, &b.velocity.ilo),
        ),
        (
            "/// ILO1, ILO2, ILO3 `(k1, l, k2)` of the acceleration half.",
            "ILO_ACCELERATION",
            "[(f32, f32, f32); 3]",
            &|w, b| write_ilo(w, &b.acceleration.ilo),
        ),
        (
            "/// AD time constant `T`, s, `[velocity, acceleration]`.",
            "AD_T",
            "[f32; 2]",
            &|w, b| write!(w, "[{:?}, {:?}]", b.velocity.ad_t, b.acceleration.ad_t),
        ),
        (
            "/// ED `(lambda, alpha)`, `[velocity, acceleration]`.",
            "ED",
            "[(f32, f32); 2]",
            &|w, b| {
                let (v, a) = (b.velocity.ed, b.acceleration.ed);
                pairs(w, (v.lambda, v.alpha), (a.lambda, a.alpha))
            },
        ),
        (
            "/// Kalman tracker `q`, deg^2/s^5, `[velocity, acceleration]`.",
            "KF_Q",
            "[f32; 2]",
            &|w, b| write!(w, "[{:?}, {:?}]", b.velocity.kf.q, b.acceleration.kf.q),
        ),
    ];
    for (i, (doc, name, ty, row)) in tables.into_iter().enumerate() {
        if i > 0 {
            w.write_str("\n")?;
        }
        writeln!(
            w,
            "{doc}\n#[rustfmt::skip]\nconst {name}: [{ty}; BANDS] = ["
        )?;
        for b in bands {
            w.write_str("    ")?;
            row(w, b)?;
            let [fast, slow] = b.tuned_period_s.map(|p| 1.0 / p);
            if fast == slow {
                writeln!(w, ", // {fast:.0} Hz")?;
            } else {
                writeln!(w, ", // {fast:.0}-{slow:.0} Hz")?;
            }
        }
        w.write_str("];\n")?;
    }
    Ok(())
}

/// An ILO row of [`write_rate_tables`]: `[(k1, l, k2), ..]`.
fn write_ilo(w: &mut dyn Write, ilo: &[IloConfig; 3]) -> fmt::Result {
    w.write_str("[")?;
    for (i, c) in ilo.iter().enumerate() {
        let sep = if i == 0 { "" } else { ", " };
        write!(w, "{sep}({:?}, {:?}, {:?})", c.k1, c.l, c.k2)?;
    }
    w.write_str("]")
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimators::{BankConfig, DeltaMode, ObserverSwitch};

    /// The paper's velocity gains as `nav440 tune --rust` writes them: every field on its own
    /// line, the ILOs one per line one level deeper, the paper's values in their `{:?}` form.
    #[test]
    fn bank_gains_literal_spells_out_every_field() {
        let want = "BankGains {
        ave: AveConfig { k: 500.0, gamma1: 20000.0, delta: DeltaMode::Paper },
        ilo: [
            IloConfig { k1: 1.0, l: 4.0, k2: 0.2 },
            IloConfig { k1: 0.9, l: 5.0, k2: 10.0 },
            IloConfig { k1: 0.7, l: 1.0, k2: 20.0 },
        ],
        ad_t: 0.01,
        ed: EdConfig { lambda: 700.0, alpha: 770.0 },
        kf: KalmanNoise { q: 1000000.0, r: 0.01 },
    }";
        assert_eq!(bank_gains_literal(&BankGains::PAPER_VELOCITY, "    "), want);
    }

    /// The `use` line names each type of a `BankGains` literal once, sorted, with the extra
    /// names.
    #[test]
    fn the_use_line_names_each_type_once() {
        assert_eq!(
            use_line(&["BankConfig", "IloConfig"]),
            "use estimators::{AveConfig, BankConfig, DeltaMode, EdConfig, IloConfig, KalmanNoise};"
        );
    }

    /// A switch point and a leaky AVE in their shortest round-trip forms.
    #[test]
    fn observer_switch_and_delta_laws_on_one_line() {
        let sw = ObserverSwitch {
            ave: 0.006565258,
            ilo: [0.1, 0.25, 3.0],
            ed: 1e-7,
        };
        assert_eq!(
            literal(&sw, ""),
            "ObserverSwitch { ave: 0.006565258, ilo: [0.1, 0.25, 3.0], ed: 1e-7 }"
        );
        assert_eq!(
            literal(&AVE_DEFAULT, ""),
            "AveConfig { k: 500.0, gamma1: 20000.0, delta: DeltaMode::Leaky { sigma: 0.1 } }"
        );
    }

    /// The tables in `estimators/src/rates.rs` are [`write_rate_tables`]' output for the bands
    /// they build, to the byte: every gain reads back from its `{:?}` form, and a re-tuned
    /// table is pasted from the printer, not edited by hand.
    #[test]
    fn the_rate_tables_are_what_write_rate_tables_prints() {
        let mut printed = String::new();
        write_rate_tables(&BankConfig::NAV440_RATES, &mut printed).unwrap();
        assert_eq!(printed.matches("#[rustfmt::skip]").count(), 7);
        assert!(printed.starts_with(
            "/// Each band's `(tuned_period_s, below_period_s)`, s (see [`RateGains`]).\n\
             #[rustfmt::skip]\n\
             const PERIODS: [([f32; 2], f32); BANDS] = [\n    ([0.01, 0.05], 0.075), // 100-20 Hz\n"
        ));
        assert!(
            include_str!("../../estimators/src/rates.rs").contains(&printed),
            "estimators/src/rates.rs does not hold the printed tables:\n{printed}"
        );
    }

    /// A band the tables cannot hold (another `deltahat` law, another tracker `r`) is refused,
    /// with nothing written.
    #[test]
    fn write_rate_tables_refuses_what_the_tables_cannot_hold() {
        let mut paper_law = BankConfig::NAV440_RATES;
        paper_law[1].velocity.ave.delta = DeltaMode::Paper;
        let mut other_r = BankConfig::NAV440_RATES;
        other_r[2].acceleration.kf.r = 0.5;
        for bands in [paper_law, other_r] {
            let mut printed = String::new();
            assert!(write_rate_tables(&bands, &mut printed).is_err());
            assert!(printed.is_empty());
        }
    }
}
