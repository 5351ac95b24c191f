//! Gains file (TOML): what `nav440 tune` writes and `--gains FILE` reads.
//!
//! ```toml
//! [velocity.ave]            # estimators::AveConfig { k, gamma1, delta }
//! k = 500.0
//! gamma1 = 20000.0
//! delta = { leaky = { sigma = 0.1 } }   # or "paper", or { bounded = { max = 1e3 } };
//!                                       # optional: left out, the base's law is kept
//! [velocity.ilo1]           # estimators::IloConfig { k1, l, k2 } (tau = h)
//! k1 = 1.0
//! l = 4.0
//! k2 = 0.2
//! # ... ilo2, ilo3
//! [velocity.ad]             # estimators::AdConfig { t }: s / (T s + 1)
//! t = 0.01
//! [velocity.ed]             # estimators::EdConfig { lambda, alpha }
//! lambda = 700.0
//! alpha = 770.0
//! [velocity.kf]             # estimators::KalmanNoise { q, r } (dt = nominal sample period)
//! q = 1e6
//! r = 0.01
//! [acceleration.ave]        # the same tables for the series (acceleration) estimators
//! ...
//! ```
//! Every table is optional (what is left out keeps the preset); within a table every key but
//! `delta` is required. The tables deserialize straight into the estimators crate's
//! configuration types (its `serde` feature).

use crate::error::{Error, Result};
use crate::rust_literal::{bank_gains_literal, literal, use_line};
use estimators::{
    for_each_family, AveFamily, BankConfig, BankGains, Family, FamilyVisitor, ObserverSwitch,
    FAMILIES, FAMILY_COUNT,
};
use estimators::{ConfigError, Gains as _};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeStruct, Serializer};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Gains of one bank half (velocity estimators or acceleration series) as a gains file holds
/// them: for each family of the paper bank ([`estimators::FAMILIES`], in column order) its
/// gains or nothing, one optional TOML table `[half.NAME]` each, in the estimators crate's
/// own configuration type ([`Family::Gains`], its `serde` feature).
#[derive(Clone, Copy, Debug)]
pub struct FamilyGains {
    /// The gains of the families present (the other families' entries are not read).
    gains: BankGains,
    /// Which families have gains here, by column.
    present: [bool; FAMILY_COUNT],
    /// The `[*.ave]` table had no `delta` key (files written before it existed): applying
    /// keeps the base configuration's `deltahat` law.
    pub ave_delta_from_base: bool,
}

impl Default for FamilyGains {
    /// No family's gains.
    fn default() -> Self {
        FamilyGains {
            gains: BankGains::PAPER_VELOCITY,
            present: [false; FAMILY_COUNT],
            ave_delta_from_base: false,
        }
    }
}

/// The column of the family `F` in [`FAMILIES`].
fn column<F: Family>() -> usize {
    FAMILIES
        .iter()
        .position(|f| f.name == F::NAME)
        .unwrap_or(usize::MAX)
}

impl PartialEq for FamilyGains {
    /// The same families present with the same gains.
    fn eq(&self, other: &Self) -> bool {
        struct Same<'a>(&'a FamilyGains, &'a FamilyGains, bool);
        impl FamilyVisitor for Same<'_> {
            fn family<F: Family>(&mut self, column: usize) {
                self.2 &= self.0.get_at::<F>(column) == self.1.get_at::<F>(column);
            }
        }
        let mut same = Same(
            self,
            other,
            self.ave_delta_from_base == other.ave_delta_from_base,
        );
        for_each_family(&mut same);
        same.2
    }
}

/// A whole gains file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GainsFile {
    /// Velocity estimators.
    #[serde(default)]
    pub velocity: FamilyGains,
    /// Acceleration (series) estimators.
    #[serde(default)]
    pub acceleration: FamilyGains,
}

impl GainsFile {
    /// Parses TOML text.
    pub fn from_toml(text: &str) -> Result<Self> {
        let table: toml::Table = toml::from_str(text)
            .map_err(|e| Error::Usage(format!("bad gains file: {}", one_line(&e.to_string()))))?;
        Self::from_table(table)
    }

    /// The gains file of a parsed TOML table.
    pub fn from_table(mut table: toml::Table) -> Result<Self> {
        let bad = |e: &dyn std::fmt::Display| {
            Error::Usage(format!("bad gains file: {}", one_line(&e.to_string())))
        };
        // `[*.ave]` without `delta`: a placeholder law, replaced by the base's on apply.
        let mut from_base = [false; 2];
        for (half, flag) in ["velocity", "acceleration"]
            .iter()
            .zip(from_base.iter_mut())
        {
            if let Some(toml::Value::Table(ave)) = table
                .get_mut(*half)
                .and_then(|h| h.as_table_mut())
                .and_then(|h| h.get_mut(AveFamily::NAME))
            {
                if !ave.contains_key("delta") {
                    ave.insert("delta".into(), toml::Value::String("paper".into()));
                    *flag = true;
                }
            }
        }
        let mut g: GainsFile = table.try_into().map_err(|e| bad(&e))?;
        g.velocity.ave_delta_from_base = from_base[0];
        g.acceleration.ave_delta_from_base = from_base[1];
        Ok(g)
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// What `--gains FILE` holds: fixed gains, or a gain schedule (noise-adaptive bank).
#[derive(Clone, Debug, PartialEq)]
pub enum Loaded {
    /// A gains file, applied over the base preset.
    Fixed(GainsFile),
    /// A schedule file (`nav440 tune --schedule`).
    Schedule(ScheduleFile),
}

/// One level of a schedule file: a noise variance and the gains tuned for it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleLevelFile {
    /// Noise variance, deg^2.
    pub noise_var: f64,
    /// Velocity gains (every table present).
    pub velocity: FamilyGains,
    /// Acceleration gains.
    pub acceleration: FamilyGains,
    /// The AVEs' switching gains these gains were tuned with, their mean over the tuning run
    /// (`estimators::ScheduleLevel::ave_deltahat`; optional: without it a gain change keeps
    /// the AVEs' `deltahat`, as files written before it was recorded do).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ave_deltahat: Option<AveDeltahatFile>,
    /// Where each observer family moves on to the next level
    /// (`estimators::ScheduleLevel::switch_up`; optional: without it, at the geometric
    /// midpoint of the two levels, as files written before it was recorded do).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub switch_up: Option<SwitchUpFile>,
}

/// The `[level.switch_up]` table of a schedule file ([`estimators::ObserverSwitch`]): the
/// noise variance (deg^2) from which each observer family takes the next level's gains, one
/// key per family that records one (`ave`, `ilo1`, `ilo2`, `ilo3`, `ed`: see
/// [`Family::switch_up_mut`]), every key required.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwitchUpFile(pub ObserverSwitch);

impl From<SwitchUpFile> for ObserverSwitch {
    fn from(w: SwitchUpFile) -> Self {
        w.0
    }
}

/// The `SwitchUpFile` struct of the file, for serde.
const SWITCH_UP: &str = "SwitchUpFile";

/// The names of the families that record a switch point, in column order (the keys of
/// [`SwitchUpFile`]).
fn switch_up_names() -> &'static [&'static str] {
    static NAMES: std::sync::OnceLock<Vec<&'static str>> = std::sync::OnceLock::new();
    NAMES.get_or_init(|| {
        let any = ObserverSwitch::all(1.0);
        any.points()
            .iter()
            .map(|&(c, _)| FAMILIES[c].name)
            .collect()
    })
}

impl Serialize for SwitchUpFile {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let points = self.0.points();
        let mut s = serializer.serialize_struct(SWITCH_UP, points.len())?;
        for &(c, x) in &points {
            s.serialize_field(FAMILIES[c].name, &x)?;
        }
        s.end()
    }
}

impl<'de> Deserialize<'de> for SwitchUpFile {
    /// As a derived struct of one required f32 field per family that records a switch point
    /// would (`deny_unknown_fields`).
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        /// A key: its index in [`switch_up_names`].
        struct Key(usize);
        impl<'de> Deserialize<'de> for Key {
            fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                struct K;
                impl Visitor<'_> for K {
                    type Value = Key;
                    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                        f.write_str("field identifier")
                    }
                    fn visit_u64<E: de::Error>(self, i: u64) -> std::result::Result<Key, E> {
                        let n = switch_up_names().len();
                        match usize::try_from(i) {
                            Ok(i) if i < n => Ok(Key(i)),
                            _ => Err(E::invalid_value(
                                de::Unexpected::Unsigned(i),
                                &format!("field index 0 <= i < {n}").as_str(),
                            )),
                        }
                    }
                    fn visit_str<E: de::Error>(self, name: &str) -> std::result::Result<Key, E> {
                        let names = switch_up_names();
                        match names.iter().position(|n| *n == name) {
                            Some(i) => Ok(Key(i)),
                            None => Err(E::unknown_field(name, names)),
                        }
                    }
                    fn visit_bytes<E: de::Error>(self, b: &[u8]) -> std::result::Result<Key, E> {
                        self.visit_str(&String::from_utf8_lossy(b))
                    }
                }
                d.deserialize_identifier(K)
            }
        }
        /// Sets the switch point of the family named `names[i]`.
        fn set(sw: &mut ObserverSwitch, i: usize, x: f32) {
            struct Set<'a>(&'a mut ObserverSwitch, &'static str, f32);
            impl FamilyVisitor for Set<'_> {
                fn family<F: Family>(&mut self, _: usize) {
                    if F::NAME == self.1 {
                        if let Some(p) = F::switch_up_mut(self.0) {
                            *p = self.2;
                        }
                    }
                }
            }
            for_each_family(&mut Set(sw, switch_up_names()[i], x));
        }
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = SwitchUpFile;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "struct {SWITCH_UP}")
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<SwitchUpFile, A::Error> {
                let names = switch_up_names();
                let mut values: Vec<Option<f32>> = vec![None; names.len()];
                while let Some(Key(i)) = map.next_key()? {
                    if values[i].is_some() {
                        return Err(de::Error::duplicate_field(names[i]));
                    }
                    values[i] = Some(map.next_value()?);
                }
                let mut sw = ObserverSwitch::all(0.0);
                for (i, v) in values.into_iter().enumerate() {
                    match v {
                        Some(x) => set(&mut sw, i, x),
                        None => return Err(de::Error::missing_field(names[i])),
                    }
                }
                Ok(SwitchUpFile(sw))
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<SwitchUpFile, A::Error> {
                let names = switch_up_names();
                let mut sw = ObserverSwitch::all(0.0);
                for i in 0..names.len() {
                    match seq.next_element()? {
                        Some(x) => set(&mut sw, i, x),
                        None => {
                            return Err(de::Error::invalid_length(
                                i,
                                &format!("struct {SWITCH_UP} with {} elements", names.len())
                                    .as_str(),
                            ))
                        }
                    }
                }
                Ok(SwitchUpFile(sw))
            }
        }
        d.deserialize_struct(SWITCH_UP, switch_up_names(), V)
    }
}

/// The `[level.ave_deltahat]` table of a schedule file (`estimators::AveDeltahat`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AveDeltahatFile {
    /// The velocity AVE's `deltahat`, deg/s.
    pub velocity: f32,
    /// The AVE-AVE series' stages', deg/s and deg/s^2.
    pub acceleration: [f32; 2],
}

impl From<AveDeltahatFile> for estimators::AveDeltahat {
    fn from(d: AveDeltahatFile) -> Self {
        estimators::AveDeltahat {
            velocity: d.velocity,
            acceleration: d.acceleration,
        }
    }
}

impl From<estimators::AveDeltahat> for AveDeltahatFile {
    fn from(d: estimators::AveDeltahat) -> Self {
        AveDeltahatFile {
            velocity: d.velocity,
            acceleration: d.acceleration,
        }
    }
}

/// A schedule file (TOML), what `nav440 tune --schedule V1,V2,.. -o FILE` writes:
///
/// ```toml
/// hold = "linear"            # the hold the levels were tuned with ("linear" or "zoh")
/// sample_period_s = 0.01     # the nominal sample period they were tuned at, s (optional)
/// [[level]]
/// noise_var = 0.001          # deg^2, increasing from level to level
/// [level.velocity.ave]       # the tables of a gains file, every one present
/// ...
/// [level.ave_deltahat]       # optional: the AVEs' deltahat this level was tuned with
/// velocity = 0.9             # deg/s
/// acceleration = [0.9, 12.0] # the AVE-AVE series' stages, deg/s and deg/s^2
/// [level.switch_up]          # optional: the noise (deg^2) from which each observer family
/// ave = 0.006                # takes the next level's gains (default: the two levels'
/// ilo1 = 0.003               # geometric midpoint)
/// ilo2 = 0.003
/// ilo3 = 0.003
/// ed = 0.002
/// [[level]]
/// noise_var = 0.01
/// ...
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleFile {
    /// The hold the levels were tuned with: "linear" or "zoh".
    pub hold: String,
    /// The nominal sample period the levels were tuned at, s (`None`: not recorded, as in
    /// files written before it was). `nav440 estimate --gains` warns when a capture's period
    /// does not fit it (`estimators::GainSchedule::fits_period`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_period_s: Option<f64>,
    /// The jerk power of the motion the levels were tuned on, (deg/s^3)^2 (`None`: not
    /// recorded; the gains then follow the noise alone). With it the bank also follows the
    /// motion: on a motion that moves far harder it takes the gains of a lower noise, on one
    /// that moves far more gently those of a higher noise
    /// (`estimators::GainSchedule::with_tuned_jerk`; the bundled fig5 capture's is 3.85e6).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tuned_jerk_power: Option<f64>,
    /// The acceleration power of the motion the levels were tuned on, (deg/s^2)^2 (`None`:
    /// not recorded; the AD then follows the jerk power as the tracker does). With it and
    /// `tuned_jerk_power`, the AD's gains follow the motion's acceleration power
    /// (`estimators::GainSchedule::with_tuned_acceleration`; the bundled fig5 capture's is
    /// 1.43e5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tuned_acceleration_power: Option<f64>,
    /// The levels, by increasing noise variance.
    pub level: Vec<ScheduleLevelFile>,
}

impl ScheduleFile {
    /// The hold named in the file.
    pub fn hold(&self) -> Result<estimators::Hold> {
        match self.hold.as_str() {
            "linear" => Ok(estimators::Hold::Linear),
            "zoh" => Ok(estimators::Hold::ZeroOrder),
            h => Err(Error::Usage(format!(
                "bad schedule file: hold must be \"linear\" or \"zoh\", got {h:?}"
            ))),
        }
    }

    /// The schedule over `base`'s gains (tables left out keep `base`'s).
    pub fn schedule(&self, base: &BankConfig) -> Result<estimators::GainSchedule> {
        let levels: Vec<estimators::ScheduleLevel> = self
            .level
            .iter()
            .map(|l| estimators::ScheduleLevel {
                noise_var: l.noise_var as f32,
                velocity: l.velocity.apply(base.velocity),
                acceleration: l.acceleration.apply(base.acceleration),
                ave_deltahat: l.ave_deltahat.map(Into::into),
                switch_up: l.switch_up.map(Into::into),
            })
            .collect();
        estimators::GainSchedule::new(&levels)
            .and_then(|s| {
                s.with_records(
                    self.sample_period_s.map(|p| p as f32),
                    self.tuned_jerk_power.map(|j| j as f32),
                    self.tuned_acceleration_power.map(|a| a as f32),
                )
            })
            .map_err(|e| Error::Usage(format!("bad schedule file: {e}")))
    }

    /// TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// A Rust snippet: the schedule's levels as a const array, the period they were tuned at
    /// and the jerk and acceleration powers of the motion they were tuned on (for the
    /// firmware: `GainSchedule::new(&SCHEDULE)`, then `with_records(SCHEDULE_PERIOD_S,
    /// SCHEDULE_TUNED_JERK, SCHEDULE_TUNED_ACCELERATION)`), over `base`'s gains.
    pub fn to_rust(&self, what: &str, base: &BankConfig) -> String {
        let opt = |x: Option<f64>| match x {
            Some(x) => format!("Some({:?})", x as f32),
            None => "None".to_string(),
        };
        let (period, jerk) = (opt(self.sample_period_s), opt(self.tuned_jerk_power));
        let acceleration = opt(self.tuned_acceleration_power);
        // `AveDeltahat` and `ObserverSwitch` only when a level records them (an unused import
        // would warn).
        let mut names = vec!["BankGains", "ScheduleLevel"];
        if self.level.iter().any(|l| l.ave_deltahat.is_some()) {
            names.push("AveDeltahat");
        }
        if self.level.iter().any(|l| l.switch_up.is_some()) {
            names.push("ObserverSwitch");
        }
        let mut s = format!(
            "// Generated by `nav440 tune` ({what}), hold {}. Build the bank with\n\
             // `AdaptiveBank::new(&BankConfig {{ hold, ..BankConfig::NAV440 }}, &schedule, &AdaptiveConfig::DEFAULT)`,\n\
             // `schedule` being\n\
             // `GainSchedule::new(&SCHEDULE)?\n\
             //     .with_records(SCHEDULE_PERIOD_S, SCHEDULE_TUNED_JERK, SCHEDULE_TUNED_ACCELERATION)?`.\n\
             {}\n\n\
             /// The nominal sample period the levels were tuned at, s.\n\
             pub const SCHEDULE_PERIOD_S: Option<f32> = {period};\n\n\
             /// The jerk power of the motion the levels were tuned on, (deg/s^3)^2.\n\
             pub const SCHEDULE_TUNED_JERK: Option<f32> = {jerk};\n\n\
             /// The acceleration power of the motion the levels were tuned on, (deg/s^2)^2.\n\
             pub const SCHEDULE_TUNED_ACCELERATION: Option<f32> = {acceleration};\n\n\
             pub const SCHEDULE: [ScheduleLevel; {}] = [\n",
            self.hold,
            use_line(&names),
            self.level.len()
        );
        for l in &self.level {
            let deltahat = match l.ave_deltahat {
                Some(d) => format!(
                    "Some(AveDeltahat {{ velocity: {:?}, acceleration: [{:?}, {:?}] }})",
                    d.velocity, d.acceleration[0], d.acceleration[1]
                ),
                None => "None".to_string(),
            };
            let switch = match l.switch_up {
                Some(SwitchUpFile(w)) => format!("Some({})", literal(&w, "")),
                None => "None".to_string(),
            };
            s.push_str(&format!(
                "    ScheduleLevel {{\n        noise_var: {:?},\n        velocity: {},\n        acceleration: {},\n        ave_deltahat: {deltahat},\n        switch_up: {switch},\n    }},\n",
                l.noise_var as f32,
                l.velocity.rust(&base.velocity, "        "),
                l.acceleration.rust(&base.acceleration, "        ")
            ));
        }
        s.push_str("];\n");
        s
    }
}

/// Checks every table of a loaded gains or schedule file `path` at the step `h` (s): a table
/// whose gains do not build their law is a usage error naming the file, the table (with the
/// level in a schedule file) and the key. Called before any capture is read.
pub fn check_tables(path: &Path, loaded: &Loaded, h: f32) -> Result<()> {
    let halves = |v: &FamilyGains, a: &FamilyGains, prefix: &str, level: Option<usize>| {
        for (half, g) in [("velocity", v), ("acceleration", a)] {
            if let Err((name, key, e)) = g.check(h) {
                let level = level.map_or(String::new(), |n| format!(" of level {n}"));
                return Err(table_error(
                    &format!("[{prefix}{half}.{name}]{level}"),
                    key.as_deref(),
                    &e,
                ));
            }
        }
        Ok(())
    };
    let (kind, r) = match loaded {
        Loaded::Fixed(g) => ("gains", halves(&g.velocity, &g.acceleration, "", None)),
        Loaded::Schedule(f) => (
            "schedule",
            f.level
                .iter()
                .enumerate()
                .try_for_each(|(i, l)| halves(&l.velocity, &l.acceleration, "level.", Some(i + 1))),
        ),
    };
    r.map_err(|m| Error::Usage(format!("{}: bad {kind} file: {m}", path.display())))
}

/// The largest gains or schedule file read, bytes (1 MiB; the shipped ones are under 4 KiB):
/// a larger file is refused before it is parsed (a 50 MB file took 4 GB to parse).
pub const MAX_GAINS_FILE_BYTES: u64 = 1 << 20;

/// Reads a gains file or a schedule file (told apart by its `[[level]]` tables). The file is
/// read up to [`MAX_GAINS_FILE_BYTES`] and parsed once.
pub fn load_any(path: &Path) -> Result<Loaded> {
    let text = read_text(path)?;
    let table = parse_table(path, &text)?;
    check_finite(path, &table)?;
    if table.contains_key("level") {
        let f: ScheduleFile = table.try_into().map_err(|e| {
            Error::Usage(format!(
                "{}: bad schedule file: {}",
                path.display(),
                one_line(&e.to_string())
            ))
        })?;
        f.hold()?;
        f.schedule(&BankConfig::NAV440)
            .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
        return Ok(Loaded::Schedule(f));
    }
    GainsFile::from_table(table)
        .map(Loaded::Fixed)
        .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))
}

/// The TOML table of a gains or schedule file's `text` (a usage error naming the file if it
/// is not TOML).
fn parse_table(path: &Path, text: &str) -> Result<toml::Table> {
    toml::from_str(text).map_err(|e| {
        Error::Usage(format!(
            "{}: bad gains file: {}",
            path.display(),
            one_line(&e.to_string())
        ))
    })
}

/// The text of a gains file: at most [`MAX_GAINS_FILE_BYTES`] (more is an input error, exit
/// 3, found while reading: nothing beyond the cap is read), UTF-8 (else a usage error).
fn read_text(path: &Path) -> Result<String> {
    use std::io::Read;
    let cannot =
        |e: std::io::Error| Error::Input(format!("cannot read gains file {}: {e}", path.display()));
    let f = std::fs::File::open(path).map_err(cannot)?;
    let mut bytes = Vec::new();
    f.take(MAX_GAINS_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(cannot)?;
    if bytes.len() as u64 > MAX_GAINS_FILE_BYTES {
        return Err(Error::Input(format!(
            "gains file {} is larger than {MAX_GAINS_FILE_BYTES} bytes (1 MiB), the most a gains or schedule file may hold (one written by `nav440 tune` is a few KiB)",
            path.display()
        )));
    }
    // A file that is not text is a bad gains file (usage error, exit 2), like bad TOML.
    String::from_utf8(bytes).map_err(|e| {
        Error::Usage(format!(
            "{}: bad gains file: not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

/// Reads a gains file (at most [`MAX_GAINS_FILE_BYTES`], parsed once) and applies it over the
/// paper presets.
pub fn load(path: &Path) -> Result<estimators::BankConfig> {
    let text = read_text(path)?;
    let table = parse_table(path, &text)?;
    check_finite(path, &table)?;
    let g = GainsFile::from_table(table)
        .map_err(|e| Error::Usage(format!("{}: {e}", path.display())))?;
    Ok(g.apply(BankConfig::default()))
}

/// Why the number `x` of a gains or schedule file cannot be used, if it cannot: not finite,
/// or beyond what the estimators' f32 holds (it would become infinite).
fn bad_number(x: f64) -> Option<&'static str> {
    if !x.is_finite() {
        Some("every number must be finite")
    } else if x.abs() > f64::from(f32::MAX) {
        Some("out of range: every number must be at most 3.4e38 in magnitude (an f32)")
    } else {
        None
    }
}

/// TOML allows `nan` and `inf`: a number of a gains or schedule file that is not finite (or
/// beyond an f32's range) is a usage error naming the file, the table (`[velocity.ilo1]`, `[level.velocity.ilo1]` with the
/// level's number) and the key.
fn check_finite(path: &Path, t: &toml::Table) -> Result<()> {
    fn walk(table: &toml::Table, name: &str, level: Option<usize>) -> Option<String> {
        for (key, v) in table {
            let here = |k: &str| {
                let level = level.map_or(String::new(), |n| format!(" of level {n}"));
                let table = if name.is_empty() {
                    "the top level".to_string()
                } else {
                    format!("[{name}]")
                };
                format!("{table}{level} key {k}")
            };
            let sub = if name.is_empty() {
                key.clone()
            } else {
                format!("{name}.{key}")
            };
            match v {
                toml::Value::Float(x) => {
                    if let Some(why) = bad_number(*x) {
                        return Some(format!("{} is {x:?}: {why}", here(key)));
                    }
                }
                toml::Value::Table(t) => {
                    if let Some(m) = walk(t, &sub, level) {
                        return Some(m);
                    }
                }
                toml::Value::Array(items) => {
                    for (i, item) in items.iter().enumerate() {
                        match item {
                            toml::Value::Table(t) => {
                                if let Some(m) = walk(t, &sub, Some(i + 1)) {
                                    return Some(m);
                                }
                            }
                            toml::Value::Float(x) => {
                                if let Some(why) = bad_number(*x) {
                                    return Some(format!(
                                        "{} item {} is {x:?}: {why}",
                                        here(key),
                                        i + 1
                                    ));
                                }
                            }
                            _ => {}
                        }
                    }
                }
                _ => {}
            }
        }
        None
    }
    match walk(t, "", None) {
        Some(m) => Err(Error::Usage(format!(
            "{}: bad {} file: {m}",
            path.display(),
            if t.contains_key("level") {
                "schedule"
            } else {
                "gains"
            }
        ))),
        None => Ok(()),
    }
}

impl FamilyGains {
    /// The gains of one bank half, every family present.
    pub fn from_bank(g: &BankGains) -> Self {
        FamilyGains {
            gains: *g,
            present: [true; FAMILY_COUNT],
            ave_delta_from_base: false,
        }
    }

    /// The family `F`'s gains, if present.
    pub fn get<F: Family>(&self) -> Option<F::Gains> {
        self.get_at::<F>(column::<F>())
    }

    /// Sets (or, with `None`, removes) the family `F`'s gains.
    pub fn set<F: Family>(&mut self, gains: Option<F::Gains>) {
        self.set_at::<F>(column::<F>(), gains);
    }

    /// [`Self::get`] for `F` at `column`.
    fn get_at<F: Family>(&self, column: usize) -> Option<F::Gains> {
        let present = self.present.get(column).copied().unwrap_or(false);
        present.then(|| F::get(&self.gains))
    }

    /// [`Self::set`] for `F` at `column`.
    fn set_at<F: Family>(&mut self, column: usize, gains: Option<F::Gains>) {
        if let Some(p) = self.present.get_mut(column) {
            *p = gains.is_some();
        }
        if let Some(g) = gains {
            F::set(&mut self.gains, g);
        }
    }

    /// These gains with only the columns `keep(i)` is true for (bank column order,
    /// [`estimators::FAMILIES`]); the others absent.
    pub fn only(&self, keep: impl Fn(usize) -> bool) -> Self {
        let mut out = *self;
        for (i, p) in out.present.iter_mut().enumerate() {
            *p &= keep(i);
        }
        out
    }

    /// Sets column `i` (bank column order) to `src`'s (absent if absent there).
    pub fn set_column(&mut self, i: usize, src: &Self) {
        struct Copy<'a>(&'a mut FamilyGains, &'a FamilyGains, usize);
        impl FamilyVisitor for Copy<'_> {
            fn family<F: Family>(&mut self, column: usize) {
                if column == self.2 {
                    self.0.set_at::<F>(column, self.1.get_at::<F>(column));
                }
            }
        }
        for_each_family(&mut Copy(self, src, i));
    }

    /// `base` with every gain present here replaced.
    pub fn apply(&self, mut base: BankGains) -> BankGains {
        struct Apply<'a>(&'a FamilyGains, &'a mut BankGains);
        impl FamilyVisitor for Apply<'_> {
            fn family<F: Family>(&mut self, column: usize) {
                if let Some(g) = self.0.get_at::<F>(column) {
                    F::set(self.1, g);
                }
            }
        }
        let delta = base.ave.delta;
        for_each_family(&mut Apply(self, &mut base));
        if self.ave_delta_from_base && self.get::<AveFamily>().is_some() {
            base.ave.delta = delta;
        }
        base
    }

    /// Checks that every table present builds its law at the step `h` (s): the first that
    /// does not, as (its table name, the key at fault if one is named, the law's error). Run
    /// before any capture is read, so a range error names the file, the table and the key.
    pub fn check(
        &self,
        h: f32,
    ) -> std::result::Result<(), (&'static str, Option<String>, ConfigError)> {
        /// Only builds the law.
        struct Builds;
        impl estimators::LawVisitor for Builds {
            type Output = ();
            fn law<L: estimators::Law<Num = f32>>(self, _: L) {}
            fn tracker(self, _: estimators::KalmanNoise) {}
        }
        struct Check<'a>(&'a FamilyGains, f32, Option<(&'static str, ConfigError)>);
        impl FamilyVisitor for Check<'_> {
            fn family<F: Family>(&mut self, column: usize) {
                if self.2.is_some() {
                    return;
                }
                if let Some(g) = self.0.get_at::<F>(column) {
                    if let Err(e) = g.build(self.1, Builds) {
                        self.2 = Some((F::NAME, e));
                    }
                }
            }
        }
        let mut c = Check(self, h, None);
        for_each_family(&mut c);
        match c.2 {
            None => Ok(()),
            Some((name, e)) => Err((name, config_error_key(&e), e)),
        }
    }

    pub(crate) fn rust(&self, base: &BankGains, indent: &str) -> String {
        bank_gains_literal(&self.apply(*base), indent)
    }
}

/// The gains-file key a law's configuration error is about, when it names one (`K1` is key
/// `k1`, `1/T` key `t`, `gamma1 / k` keys `gamma1` and `k`).
fn config_error_key(e: &ConfigError) -> Option<String> {
    let p = match *e {
        ConfigError::NotFinite(p)
        | ConfigError::NotPositive(p)
        | ConfigError::Negative(p)
        | ConfigError::StepTooLarge(p)
        | ConfigError::StepRateTooLarge(p) => p,
        ConfigError::K1OutOfRange => "K1",
        _ => return None,
    };
    let key = match p {
        "1/T" => "t".to_string(),
        "gamma1 / k" => "gamma1 and k".to_string(),
        p => p.to_ascii_lowercase(),
    };
    Some(key)
}

/// The message of a table that does not build: `[velocity.ilo1] key k1: K1 must be in (0, 1]`
/// (`where_` the table's name with the level, e.g. `[level.velocity.ilo1] of level 2`).
pub fn table_error(where_: &str, key: Option<&str>, e: &ConfigError) -> String {
    match key {
        Some(k) => format!("{where_} key {k}: {e}"),
        None => format!("{where_}: {e}"),
    }
}

/// The `FamilyGains` struct of the file, for serde: its fields are the families' names.
const FAMILY_GAINS: &str = "FamilyGains";

impl Serialize for FamilyGains {
    /// One field per family, `None` for an absent one (TOML leaves it out), in column order.
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        struct Fields<'a, M: SerializeStruct>(&'a FamilyGains, M, Option<M::Error>);
        impl<M: SerializeStruct> FamilyVisitor for Fields<'_, M> {
            fn family<F: Family>(&mut self, column: usize) {
                if self.2.is_none() {
                    let g = self.0.get_at::<F>(column);
                    if let Err(e) = self.1.serialize_field(F::NAME, &g) {
                        self.2 = Some(e);
                    }
                }
            }
        }
        let s = serializer.serialize_struct(FAMILY_GAINS, FAMILY_COUNT)?;
        let mut fields = Fields(self, s, None);
        for_each_family(&mut fields);
        match fields.2 {
            Some(e) => Err(e),
            None => fields.1.end(),
        }
    }
}

/// A key of the gains file's `[half]` table: the column of the family it names.
struct FamilyKey(usize);

impl<'de> Deserialize<'de> for FamilyKey {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Key;
        impl Visitor<'_> for Key {
            type Value = FamilyKey;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("field identifier")
            }
            fn visit_u64<E: de::Error>(self, i: u64) -> std::result::Result<FamilyKey, E> {
                match usize::try_from(i) {
                    Ok(i) if i < FAMILY_COUNT => Ok(FamilyKey(i)),
                    _ => Err(E::invalid_value(
                        de::Unexpected::Unsigned(i),
                        &format!("field index 0 <= i < {FAMILY_COUNT}").as_str(),
                    )),
                }
            }
            fn visit_str<E: de::Error>(self, name: &str) -> std::result::Result<FamilyKey, E> {
                match FAMILIES.iter().position(|f| f.name == name) {
                    Some(i) => Ok(FamilyKey(i)),
                    None => Err(E::unknown_field(name, &estimators::VELOCITY_NAMES)),
                }
            }
            fn visit_bytes<E: de::Error>(self, b: &[u8]) -> std::result::Result<FamilyKey, E> {
                self.visit_str(&String::from_utf8_lossy(b))
            }
        }
        d.deserialize_identifier(Key)
    }
}

/// Reads the next value of a map or the next element of a sequence.
trait ReadNext<E> {
    /// The next value as a `T`; `Ok(None)` at the end of a sequence.
    fn next<T: de::DeserializeOwned>(&mut self) -> std::result::Result<Option<T>, E>;
}

/// The next value of a map ([`MapAccess::next_value`]).
struct ValueOf<'a, A>(&'a mut A);
impl<'de, A: MapAccess<'de>> ReadNext<A::Error> for ValueOf<'_, A> {
    fn next<T: de::DeserializeOwned>(&mut self) -> std::result::Result<Option<T>, A::Error> {
        self.0.next_value().map(Some)
    }
}

/// The next element of a sequence ([`SeqAccess::next_element`]).
struct ElementOf<'a, A>(&'a mut A);
impl<'de, A: SeqAccess<'de>> ReadNext<A::Error> for ElementOf<'_, A> {
    fn next<T: de::DeserializeOwned>(&mut self) -> std::result::Result<Option<T>, A::Error> {
        self.0.next_element()
    }
}

/// Reads the family at `column` (its `Option<Gains>`, as a derived struct's field) with
/// `read` into `out`; `Ok(false)` if there was nothing to read.
fn read_one<E, R: ReadNext<E>>(
    column: usize,
    out: &mut FamilyGains,
    read: R,
) -> std::result::Result<bool, E> {
    struct Read<'a, E, R> {
        column: usize,
        out: &'a mut FamilyGains,
        read: R,
        result: std::result::Result<bool, E>,
    }
    impl<E, R: ReadNext<E>> FamilyVisitor for Read<'_, E, R> {
        fn family<F: Family>(&mut self, column: usize) {
            if column == self.column {
                self.result = self.read.next::<Option<F::Gains>>().map(|g| match g {
                    Some(g) => {
                        self.out.set_at::<F>(column, g);
                        true
                    }
                    None => false,
                });
            }
        }
    }
    let mut r = Read {
        column,
        out,
        read,
        result: Ok(false),
    };
    for_each_family(&mut r);
    r.result
}

impl<'de> Deserialize<'de> for FamilyGains {
    /// As a derived struct of one `Option` field per family would (`deny_unknown_fields`).
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Gains;
        impl<'de> Visitor<'de> for Gains {
            type Value = FamilyGains;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "struct {FAMILY_GAINS}")
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<FamilyGains, A::Error> {
                let mut out = FamilyGains::default();
                let mut seen = [false; FAMILY_COUNT];
                while let Some(FamilyKey(i)) = map.next_key()? {
                    if std::mem::replace(&mut seen[i], true) {
                        return Err(de::Error::duplicate_field(FAMILIES[i].name));
                    }
                    read_one(i, &mut out, ValueOf(&mut map))?;
                }
                Ok(out)
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<FamilyGains, A::Error> {
                let mut out = FamilyGains::default();
                for i in 0..FAMILY_COUNT {
                    if !read_one(i, &mut out, ElementOf(&mut seq))? {
                        return Err(de::Error::invalid_length(
                            i,
                            &format!("struct {FAMILY_GAINS} with {FAMILY_COUNT} elements").as_str(),
                        ));
                    }
                }
                Ok(out)
            }
        }
        d.deserialize_struct(FAMILY_GAINS, &estimators::VELOCITY_NAMES, Gains)
    }
}
impl GainsFile {
    /// The gains of a bank configuration.
    pub fn from_bank(cfg: &BankConfig) -> Self {
        GainsFile {
            velocity: FamilyGains::from_bank(&cfg.velocity),
            acceleration: FamilyGains::from_bank(&cfg.acceleration),
        }
    }

    /// `base` with every gain present here replaced (step, hold, gap and period untouched).
    pub fn apply(&self, mut base: BankConfig) -> BankConfig {
        base.velocity = self.velocity.apply(base.velocity);
        base.acceleration = self.acceleration.apply(base.acceleration);
        base
    }

    /// A Rust snippet that builds the same configuration (for the firmware's `BankConfig`),
    /// to pass to `bank::new` (`bank`: the bank's type name, e.g. `PaperBank`).
    pub fn to_rust(&self, what: &str, bank: &str) -> String {
        let base = BankConfig::PAPER;
        format!(
            "// Generated by `nav440 tune` ({what}). Paste into the firmware and pass to `{bank}::new`.\n\
             {}\n\n\
             pub const TUNED: BankConfig = BankConfig {{\n    velocity: {},\n    acceleration: {},\n    ..BankConfig::PAPER\n}};\n",
            use_line(&["BankConfig", "BankGains"]),
            self.velocity.rust(&base.velocity, "    "),
            self.acceleration.rust(&base.acceleration, "    ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimators::{DeltaMode, IloConfig, IloFamily};

    #[test]
    fn paper_gains_round_trip_through_toml() {
        let paper = GainsFile::from_bank(&BankConfig::PAPER);
        let back = GainsFile::from_toml(&paper.to_toml()).unwrap();
        assert_eq!(back, paper);
        assert_eq!(back.apply(BankConfig::PAPER), BankConfig::PAPER);
        // Table 2, ILO3 and Table 4, ILO2 as the paper gives them.
        assert_eq!(
            paper.velocity.get::<IloFamily<2>>(),
            Some(IloConfig {
                k1: 0.7,
                l: 1.0,
                k2: 20.0
            })
        );
        assert_eq!(
            paper.acceleration.get::<IloFamily<1>>(),
            Some(IloConfig {
                k1: 0.9,
                l: 3.0,
                k2: 3.333
            })
        );
    }

    /// `[*.ave]` without `delta` (every gains file written before the key existed) keeps the
    /// base configuration's law; with `delta` the file's law is used.
    #[test]
    fn ave_delta_is_optional() {
        let old = GainsFile::from_toml("[velocity.ave]\nk = 300.0\ngamma1 = 9000.0\n").unwrap();
        let cfg = old.apply(BankConfig::DEFAULT);
        assert_eq!(cfg.velocity.ave.k, 300.0);
        assert_eq!(cfg.velocity.ave.delta, DeltaMode::Leaky { sigma: 0.1 });
        assert_eq!(
            old.apply(BankConfig::PAPER).velocity.ave.delta,
            DeltaMode::Paper
        );
        let new = GainsFile::from_toml(
            "[acceleration.ave]\nk = 300.0\ngamma1 = 9000.0\ndelta = { bounded = { max = 50.0 } }\n",
        )
        .unwrap();
        let cfg = new.apply(BankConfig::DEFAULT);
        assert_eq!(cfg.acceleration.ave.delta, DeltaMode::Bounded { max: 50.0 });
        assert_eq!(cfg.velocity, BankConfig::DEFAULT.velocity);
        assert!(
            GainsFile::from_toml("[velocity.ave]\nk = 1.0\ngamma1 = 2.0\ndelta = \"huge\"\n")
                .is_err()
        );
        // What `tune` writes now names the law and reads back to the same configuration.
        let g = GainsFile::from_bank(&BankConfig::DEFAULT);
        let text = g.to_toml();
        assert!(
            text.contains("[velocity.ave]") && text.contains("leaky"),
            "{text}"
        );
        assert_eq!(
            GainsFile::from_toml(&text)
                .unwrap()
                .apply(BankConfig::PAPER),
            BankConfig {
                ..BankConfig::DEFAULT
            }
        );
    }

    #[test]
    fn partial_files_override_only_what_they_name() {
        let g = GainsFile::from_toml("[acceleration.ad]\nt = 0.05\n").unwrap();
        let cfg = g.apply(BankConfig::PAPER);
        assert_eq!(cfg.acceleration.ad_t, 0.05);
        assert_eq!(cfg.velocity, BankConfig::PAPER.velocity);
        assert!(
            GainsFile::from_toml("[velocity.ave]\nk = 1.0\n").is_err(),
            "gamma1 missing"
        );
        assert!(
            GainsFile::from_toml("[velocity.avx]\nk = 1.0\n").is_err(),
            "unknown table"
        );
    }

    /// The schedule file's `tuned_jerk_power` reaches the schedule (and round-trips; the
    /// bundled file records its capture's); absent, the schedule records none; not positive,
    /// the file is refused.
    #[test]
    fn a_schedule_file_records_its_tuning_jerk() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/gains/schedule_fig5.toml"
        ));
        let Ok(Loaded::Schedule(file)) = load_any(path) else {
            panic!("not a schedule");
        };
        assert_eq!(
            file.schedule(&BankConfig::NAV440).unwrap().tuned_jerk(),
            Some(3_850_048.0)
        );
        let without = ScheduleFile {
            tuned_jerk_power: None,
            ..file.clone()
        };
        assert_eq!(
            without.schedule(&BankConfig::NAV440).unwrap().tuned_jerk(),
            None
        );
        let with = ScheduleFile {
            tuned_jerk_power: Some(3.68e6),
            ..file.clone()
        };
        let back: ScheduleFile = toml::from_str(&with.to_toml()).unwrap();
        assert_eq!(back.tuned_jerk_power, Some(3.68e6));
        let s = back.schedule(&BankConfig::NAV440).unwrap();
        assert_eq!(s.tuned_jerk(), Some(3.68e6));
        let bad = ScheduleFile {
            tuned_jerk_power: Some(0.0),
            ..file
        };
        assert!(bad.schedule(&BankConfig::NAV440).is_err());
    }
}
