//! The Rust source `nav440 tune --rust` writes for a firmware: each gains value as the
//! expression that builds it ([`RustLiteral`], implemented here for the estimators crate's
//! configuration types), the `use estimators::{..}` line those expressions need, and the
//! shipped preset's rate tables as `estimators/src/rates.rs` holds them
//! ([`write_rate_tables`]).
//!
//! Every gain is written with `{:?}`, its shortest form that reads back to the same `f32`.

use std::fmt::{self, Write};

use estimators::presets::AVE_DEFAULT;
use estimators::{
    AveConfig, BankGains, EdConfig, IloConfig, KalmanNoise, ObserverSwitch, RateGains, KF_DEFAULT,
};

/// Writes a value as the Rust expression that builds it: what [`bank_gains_literal`] writes
/// for each field of a [`BankGains`] (and so what `nav440 tune --rust` prints).
pub trait RustLiteral {
    /// Adds the type names the expression uses to `names` (for a `use estimators::{..}`
    /// line; a name may repeat).
    fn rust_types(&self, names: &mut Vec<&'static str>);

    /// Writes the expression. Where it breaks the line, the next line starts with `indent`
    /// (the indentation of the line the expression starts on) plus its own indentation.
    fn write_rust(&self, w: &mut dyn Write, indent: Indent<'_>) -> fmt::Result;
}

/// The indentation of a line of generated Rust: `base`, then four spaces per level.
#[derive(Clone, Copy, Debug)]
pub struct Indent<'a> {
    /// What every line starts with.
    pub base: &'a str,
    /// Levels of four spaces after `base`.
    pub levels: usize,
}

impl Indent<'_> {
    /// One level deeper.
    pub fn deeper(self) -> Self {
        Self {
            levels: self.levels + 1,
            ..self
        }
    }
}

impl fmt::Display for Indent<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.base)?;
        for _ in 0..self.levels {
            f.write_str("    ")?;
        }
        Ok(())
    }
}

/// A bare gain (e.g. the AD's time constant, s).
impl RustLiteral for f32 {
    fn rust_types(&self, _: &mut Vec<&'static str>) {}

    fn write_rust(&self, w: &mut dyn Write, _: Indent<'_>) -> fmt::Result {
        write!(w, "{self:?}")
    }
}

/// One element per line, one level deeper than the `[`.
impl<T: RustLiteral, const N: usize> RustLiteral for [T; N] {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        for x in self {
            x.rust_types(names);
        }
    }

    fn write_rust(&self, w: &mut dyn Write, indent: Indent<'_>) -> fmt::Result {
        w.write_str("[\n")?;
        for x in self {
            write!(w, "{}", indent.deeper())?;
            x.write_rust(w, indent.deeper())?;
            w.write_str(",\n")?;
        }
        write!(w, "{indent}]")
    }
}

/// On one line: `AveConfig { k: .., gamma1: .., delta: DeltaMode::.. }`.
impl RustLiteral for AveConfig {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        names.extend(["AveConfig", "DeltaMode"]);
    }

    fn write_rust(&self, w: &mut dyn Write, _: Indent<'_>) -> fmt::Result {
        write!(
            w,
            "AveConfig {{ k: {:?}, gamma1: {:?}, delta: DeltaMode::{:?} }}",
            self.k, self.gamma1, self.delta
        )
    }
}

/// On one line: `IloConfig { k1: .., l: .., k2: .. }`.
impl RustLiteral for IloConfig {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        names.push("IloConfig");
    }

    fn write_rust(&self, w: &mut dyn Write, _: Indent<'_>) -> fmt::Result {
        write!(
            w,
            "IloConfig {{ k1: {:?}, l: {:?}, k2: {:?} }}",
            self.k1, self.l, self.k2
        )
    }
}

/// On one line: `EdConfig { lambda: .., alpha: .. }`.
impl RustLiteral for EdConfig {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        names.push("EdConfig");
    }

    fn write_rust(&self, w: &mut dyn Write, _: Indent<'_>) -> fmt::Result {
        write!(
            w,
            "EdConfig {{ lambda: {:?}, alpha: {:?} }}",
            self.lambda, self.alpha
        )
    }
}

/// On one line: `KalmanNoise { q: .., r: .. }`.
impl RustLiteral for KalmanNoise {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        names.push("KalmanNoise");
    }

    fn write_rust(&self, w: &mut dyn Write, _: Indent<'_>) -> fmt::Result {
        write!(w, "KalmanNoise {{ q: {:?}, r: {:?} }}", self.q, self.r)
    }
}

/// `BankGains { .. }` with every field spelled out on its own line, one level deeper than the
/// `BankGains`.
impl RustLiteral for BankGains {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        let BankGains {
            ave,
            ilo,
            ad_t,
            ed,
            kf,
        } = self;
        ave.rust_types(names);
        ilo.rust_types(names);
        ad_t.rust_types(names);
        ed.rust_types(names);
        kf.rust_types(names);
    }

    fn write_rust(&self, w: &mut dyn Write, indent: Indent<'_>) -> fmt::Result {
        // Every field by name: a field added to `BankGains` does not compile here until it is
        // written too.
        let BankGains {
            ave,
            ilo,
            ad_t,
            ed,
            kf,
        } = self;
        let fields: [(&str, &dyn RustLiteral); 5] = [
            ("ave", ave),
            ("ilo", ilo),
            ("ad_t", ad_t),
            ("ed", ed),
            ("kf", kf),
        ];
        let field = indent.deeper();
        w.write_str("BankGains {\n")?;
        for (name, value) in fields {
            write!(w, "{field}{name}: ")?;
            value.write_rust(w, field)?;
            w.write_str(",\n")?;
        }
        write!(w, "{indent}}}")
    }
}

/// On one line: `ObserverSwitch { ave: .., ilo: [..], ed: .. }`.
impl RustLiteral for ObserverSwitch {
    fn rust_types(&self, names: &mut Vec<&'static str>) {
        names.push("ObserverSwitch");
    }

    fn write_rust(&self, w: &mut dyn Write, _: Indent<'_>) -> fmt::Result {
        let ObserverSwitch {
            ave,
            ilo: [i1, i2, i3],
            ed,
        } = self;
        write!(
            w,
            "ObserverSwitch {{ ave: {ave:?}, ilo: [{i1:?}, {i2:?}, {i3:?}], ed: {ed:?} }}"
        )
    }
}

/// `value` as a Rust expression ([`RustLiteral::write_rust`]) whose continuation lines start
/// with `indent`.
pub fn literal(value: &dyn RustLiteral, indent: &str) -> String {
    let mut s = String::new();
    // Writing to a String does not fail.
    let _ = value.write_rust(
        &mut s,
        Indent {
            base: indent,
            levels: 0,
        },
    );
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
    BankGains::PAPER_VELOCITY.rust_types(&mut types);
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
    use estimators::{BankConfig, DeltaMode};

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
