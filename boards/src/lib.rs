//! The boards the firmware is built for, described once, in [`BOARDS`]
//! (`boards/src/description.rs`).
//!
//! * firmware-example's build script takes the board of the `board-*` feature (the default
//!   board without one, [`select`]), declares the board's module ([`Board::module_decl`]) and
//!   links the memory map generated from it ([`Board::linker_map`]);
//! * firmware-embassy's build script takes the board of its chip feature
//!   ([`Board::embassy_feature`], [`select_embassy`]) and links the same generated map;
//! * xtask checks every image's ELF against its board's memories ([`find`]), flashes with its
//!   probe-rs chip and builds the boards QEMU cannot run ([`Board::qemu`]).
//!
//! A board firmware-example has no image of ([`Board::example`] false) is firmware-embassy's
//! only: it has no `board-*` feature and no module.
//!
//! The build scripts include this file as a module (`#[path]`) instead of depending on the
//! crate: a build-dependency would change the firmware crate's metadata hash, hence its
//! symbol names and, through fat LTO, its code. So this crate depends on nothing but `std`.
//!
//! The figures of the description are the chips' (reference manuals, data sheets); the tests
//! of this crate hold them once more, as literals.

#![forbid(unsafe_code)]

mod description;
pub use description::BOARDS;

/// Where the description is, for messages.
pub const DESCRIPTION_PATH: &str = "boards/src/description.rs";

/// One board: what the firmware image is built for, and what checks and flashes it.
#[derive(Clone, Copy, Debug)]
pub struct Board {
    /// The board's name: `NAV440_BOARD` in the ELF, feature `board-<name>`, module `<name>`
    /// with `_` for `-` (lower-case letters, digits and single `-`).
    pub name: &'static str,
    /// What it is, for messages.
    pub part: &'static str,
    /// Selected when no `board-*` feature is (exactly one board).
    pub default: bool,
    /// firmware-example has an image of the board (its module `src/board/<module>.rs`, its
    /// feature `board-<name>` unless it is the default); `false` for a board only
    /// firmware-embassy builds for.
    pub example: bool,
    /// The shared module of `firmware-example/src/board/` the board's module builds on.
    pub backend: Option<&'static str>,
    /// The Rust targets its images are built for (the first is CI's for a built-only board).
    pub targets: &'static [&'static str],
    /// The probe-rs chip name, `None` for an emulated-only board.
    pub probe_chip: Option<&'static str>,
    /// The QEMU machines that run its image; none: the board is built and checked only.
    pub qemu: &'static [&'static str],
    /// firmware-embassy's feature for this board's chip, if it builds for it.
    pub embassy_feature: Option<&'static str>,
    /// The NAV440 UART.
    pub uart: Uart,
    /// Non-volatile code memory.
    pub flash: Region,
    /// Static RAM for `.data`, `.bss` and the stack.
    pub ram: Region,
    /// A boot loader at the start of flash, before the vector table.
    pub boot_loader: Option<BootLoader>,
    /// The image `cargo xtask ci` builds, lints and map-checks for a board no emulator runs.
    pub ci_image: Image,
}

/// A firmware-example image of a board: what it is built with beside `board-<name>`.
#[derive(Clone, Copy, Debug)]
pub struct Image {
    /// firmware-example features (the bank, the axes), beside the board's feature.
    pub features: &'static [&'static str],
    /// The cargo profile (`release`, `small`).
    pub profile: &'static str,
    /// `cargo xtask ci` builds and checks it; `false` leaves it out, with a line saying so.
    pub in_ci: bool,
    /// The emulated image whose stack stands for this one's (a board no emulator runs), or
    /// `None`.
    pub stack_twin: Option<Twin>,
}

/// An emulated stand-in for a board image's stack: the same firmware, bank, features and
/// profile, built for a QEMU board of the same core instead of the board, whose painted
/// stack `cargo xtask ci` measures through a boot and a stream and through a replay. The
/// board's image must then fit its RAM: its static RAM (from its ELF), plus the twin's
/// high-water mark, plus a margin for the frames the two boards' code differ in.
#[derive(Clone, Copy, Debug)]
pub struct Twin {
    /// The QEMU board (`cargo xtask qemu --board`), with the board's instruction set.
    pub qemu_board: &'static str,
    /// firmware-example features the board's feature implies beside its board code (the twin
    /// is built with them, without the board feature).
    pub features: &'static [&'static str],
}

impl Image {
    /// The firmware's default image: the paper bank, three axes, profile `release`.
    pub const PAPER: Image = Image {
        features: &[],
        profile: "release",
        in_ci: true,
        stack_twin: None,
    };
}

/// The UART the NAV440 is wired to.
#[derive(Clone, Copy, Debug)]
pub struct Uart {
    /// The peripheral.
    pub peripheral: &'static str,
    /// Transmit pin (none on an emulated board).
    pub tx: Option<&'static str>,
    /// Receive pin.
    pub rx: Option<&'static str>,
    /// The pins' function (alternate function).
    pub function: Option<&'static str>,
}

/// An address range of the chip.
#[derive(Clone, Copy, Debug)]
pub struct Region {
    /// Name for messages.
    pub name: &'static str,
    /// First address.
    pub origin: u64,
    /// What the chip has, KiB.
    pub kib: u64,
    /// What the memory map gives the linker, KiB from the origin, when less than [`Self::kib`].
    pub link_kib: Option<u64>,
}

/// A boot loader the image carries at the start of flash.
#[derive(Clone, Copy, Debug)]
pub struct BootLoader {
    /// Its size, bytes.
    pub bytes: u64,
    /// The input section that holds it.
    pub section: &'static str,
    /// The symbol that defines it (kept although no code refers to it).
    pub symbol: &'static str,
}

impl Region {
    /// Bytes the chip has.
    pub fn length(&self) -> u64 {
        self.kib << 10
    }

    /// Bytes the memory map gives the linker.
    pub fn link_length(&self) -> u64 {
        self.link_kib.unwrap_or(self.kib) << 10
    }

    /// Whether `len` bytes from `start` lie inside the chip's range.
    pub fn contains(&self, start: u64, len: u64) -> bool {
        start >= self.origin && start.saturating_add(len) <= self.origin + self.length()
    }

    /// Whether `len` bytes from `start` lie inside what the memory map gives the linker
    /// ([`Self::link_length`] from the origin).
    pub fn link_contains(&self, start: u64, len: u64) -> bool {
        start >= self.origin && start.saturating_add(len) <= self.origin + self.link_length()
    }
}

impl Board {
    /// The module of `firmware-example/src/board/` (the name with `_` for `-`).
    pub fn module(&self) -> String {
        self.name.replace('-', "_")
    }

    /// The firmware-example feature that selects it, `None` for the default board.
    pub fn feature(&self) -> Option<String> {
        (self.example && !self.default).then(|| format!("board-{}", self.name))
    }

    /// Where the vector table must be: the flash origin, after the boot loader if any.
    pub fn vector_table(&self) -> u64 {
        self.flash.origin + self.boot_loader.as_ref().map_or(0, |b| b.bytes)
    }

    /// Whether QEMU runs its image (else it is built and checked only).
    pub fn runs_in_qemu(&self) -> bool {
        !self.qemu.is_empty()
    }

    /// The NAV440 wiring, e.g. `USART1: TX PA9, RX PA10, AF7`.
    pub fn wiring(&self) -> String {
        let u = &self.uart;
        let parts: Vec<String> = [("TX ", u.tx), ("RX ", u.rx), ("", u.function)]
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| format!("{k}{v}")))
            .collect();
        if parts.is_empty() {
            u.peripheral.to_owned()
        } else {
            format!("{}: {}", u.peripheral, parts.join(", "))
        }
    }

    /// The Rust source that makes the board's module the firmware's `board` module: the macro
    /// `board_modules!`, which `firmware-example/src/board/mod.rs` includes and invokes. Its
    /// `mod` items (the backend module, if any, and the board's) are thus resolved in that
    /// directory, with the same relative source paths as hand-written ones; it also defines
    /// [`Self::name`] as `NAME`.
    pub fn module_decl(&self) -> String {
        let mut s = format!(
            "// The board `{}` of {DESCRIPTION_PATH}.\nmacro_rules! board_modules {{\n    () => {{\n",
            self.name
        );
        if let Some(b) = self.backend {
            s += &format!("        mod {b};\n");
        }
        let m = self.module();
        s += &format!("        mod {m};\n        pub use {m}::*;\n");
        s += &format!(
            "        /// The board's name (`NAV440_BOARD` in the ELF).\n        pub const NAME: &str = {:?};\n    }};\n}}\n",
            self.name
        );
        s
    }

    /// The memory map cortex-m-rt's `link.x` includes (`memory.x`): `FLASH` from the vector
    /// table, `RAM`, and the boot loader's region and output section when there is one.
    pub fn linker_map(&self) -> String {
        let (f, r) = (&self.flash, &self.ram);
        let mut s = format!(
            "/* {}: {}. Generated from {DESCRIPTION_PATH}. */\nMEMORY\n{{\n",
            self.name, self.part
        );
        let boot = self.boot_loader.as_ref().map(|b| {
            let region = b.section.trim_start_matches('.').to_uppercase();
            (b, region)
        });
        if let Some((b, region)) = &boot {
            s += &format!(
                "  {region} : ORIGIN = {:#010x}, LENGTH = {}\n",
                f.origin,
                size(b.bytes)
            );
        }
        let skip = self.vector_table() - f.origin;
        s += &format!(
            "  FLASH : ORIGIN = {:#010x}, LENGTH = {}\n",
            self.vector_table(),
            size(f.link_length() - skip)
        );
        s += &format!(
            "  RAM   : ORIGIN = {:#010x}, LENGTH = {}\n}}\n",
            r.origin,
            size(r.link_length())
        );
        if let Some((b, region)) = &boot {
            s += &format!(
                "\n/* The boot loader is defined in a library: keep it. */\nEXTERN({})\n\nSECTIONS\n{{\n  {} ORIGIN({region}) :\n  {{\n    KEEP(*({}));\n  }} > {region}\n}} INSERT BEFORE .text;\n",
                b.symbol, b.section, b.section
            );
        }
        s
    }
}

/// `bytes` as a linker script length: `K` when whole KiB.
fn size(bytes: u64) -> String {
    if bytes.is_multiple_of(1024) {
        format!("{}K", bytes >> 10)
    } else {
        format!("{bytes:#x}")
    }
}

/// Checks a description: names unique and usable as feature and module names, parts usable
/// in a linker script comment, exactly one default board, every board with a thumb target,
/// memories inside the 32-bit address space and apart, link sizes within the chip's, the
/// vector table in flash and aligned, chip features unique.
pub fn validate(boards: &[Board]) -> Result<(), String> {
    for (i, b) in boards.iter().enumerate() {
        let n = b.name;
        let ok = n.starts_with(|c: char| c.is_ascii_lowercase())
            && n.chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-');
        if !ok || n.ends_with('-') || n.contains("--") {
            return Err(format!(
                "board `{n}`: a name is lower-case letters, digits and single `-`"
            ));
        }
        if b.part.contains("*/") {
            return Err(format!(
                "board `{n}`: the part goes into a linker script comment: no `*/`"
            ));
        }
        let earlier = &boards[..i];
        if earlier.iter().any(|e| e.name == n) {
            return Err(format!("board `{n}` is described twice"));
        }
        if let Some(f) = b.embassy_feature {
            if earlier.iter().any(|e| e.embassy_feature == Some(f)) {
                return Err(format!(
                    "board `{n}`: embassy feature `{f}` is another board's"
                ));
            }
        }
        if b.targets.is_empty() || b.targets.iter().any(|t| !t.starts_with("thumb")) {
            return Err(format!(
                "board `{n}`: targets must be thumb targets, at least one"
            ));
        }
        for r in [&b.flash, &b.ram] {
            if r.kib == 0 || r.origin + r.length() > 1 << 32 {
                return Err(format!(
                    "board `{n}`: {} must be inside the 32-bit address space and not empty",
                    r.name
                ));
            }
            if r.link_kib.is_some_and(|l| l == 0 || l > r.kib) {
                return Err(format!(
                    "board `{n}`: {}'s link_kib must be between 1 and its kib ({})",
                    r.name, r.kib
                ));
            }
        }
        let (f, r) = (&b.flash, &b.ram);
        if f.origin < r.origin + r.length() && r.origin < f.origin + f.length() {
            return Err(format!("board `{n}`: {} and {} overlap", f.name, r.name));
        }
        let skip = b.vector_table() - f.origin;
        if skip >= f.link_length() || !b.vector_table().is_multiple_of(128) {
            return Err(format!(
                "board `{n}`: the vector table ({:#x}) must lie in flash, 128-byte aligned",
                b.vector_table()
            ));
        }
    }
    match boards.iter().filter(|b| b.default).count() {
        1 => Ok(()),
        k => Err(format!(
            "exactly one board must be `default: true` ({k} are)"
        )),
    }
}

/// Every board of the description, checked ([`validate`]).
///
/// # Panics
///
/// If the description does not pass [`validate`] (the tests of this crate check it does).
pub fn all() -> &'static [Board] {
    if let Err(e) = validate(BOARDS) {
        panic!("{DESCRIPTION_PATH}: {e}");
    }
    BOARDS
}

/// The board named `name`.
pub fn find(name: &str) -> Result<&'static Board, String> {
    all().iter().find(|b| b.name == name).ok_or_else(|| {
        let names: Vec<_> = all().iter().map(|b| b.name).collect();
        format!(
            "unknown board `{name}` (known: {}; {DESCRIPTION_PATH})",
            names.join(", ")
        )
    })
}

/// The default board (selected by no feature).
pub fn default_board() -> &'static Board {
    all()
        .iter()
        .find(|b| b.default)
        .expect("parse checks there is one")
}

/// Cargo's environment variable of feature `feature` (`board-rp-pico` ->
/// `CARGO_FEATURE_BOARD_RP_PICO`).
pub fn feature_env(feature: &str) -> String {
    format!("CARGO_FEATURE_{}", feature.to_uppercase().replace('-', "_"))
}

/// What a firmware's build script needs first: the description checked ([`validate`], its
/// error prefixed with [`DESCRIPTION_PATH`]) and the board that `select` (e.g. [`select`] or
/// [`select_embassy`]) picks from the build's enabled features (Cargo's `CARGO_FEATURE_*`
/// environment variables).
pub fn board_of_build(
    select: fn(&[String]) -> Result<&'static Board, String>,
) -> Result<&'static Board, String> {
    validate(BOARDS).map_err(|e| format!("{DESCRIPTION_PATH}: {e}"))?;
    let enabled: Vec<String> = std::env::vars()
        .map(|(k, _)| k)
        .filter(|k| k.starts_with("CARGO_FEATURE_"))
        .collect();
    select(&enabled)
}

/// The board of a firmware-example build whose enabled features' environment variables are
/// `enabled` (`CARGO_FEATURE_*`): the one whose `board-*` feature is set, the default board
/// without one; an error for two, or for a `board-*` feature without a description.
pub fn select(enabled: &[String]) -> Result<&'static Board, String> {
    let prefix = feature_env("board-");
    let mut picked = Vec::new();
    for var in enabled.iter().filter(|v| v.starts_with(&prefix)) {
        let b = all()
            .iter()
            .find(|b| b.feature().is_some_and(|f| feature_env(&f) == *var))
            .ok_or_else(|| format!("feature {var} names no board of {DESCRIPTION_PATH}"))?;
        picked.push(b);
    }
    match picked.as_slice() {
        [] => Ok(default_board()),
        [b] => Ok(b),
        many => Err(format!(
            "select at most one board-* feature (got {})",
            many.iter().map(|b| b.name).collect::<Vec<_>>().join(", ")
        )),
    }
}

/// The board of a firmware-embassy build whose enabled features' environment variables are
/// `enabled`: exactly one chip feature.
pub fn select_embassy(enabled: &[String]) -> Result<&'static Board, String> {
    let picked: Vec<_> = all()
        .iter()
        .filter(|b| {
            b.embassy_feature
                .is_some_and(|f| enabled.contains(&feature_env(f)))
        })
        .collect();
    match picked.as_slice() {
        [b] => Ok(b),
        _ => {
            let features: Vec<_> = all().iter().filter_map(|b| b.embassy_feature).collect();
            Err(format!(
                "firmware-embassy: enable exactly one chip feature: {}",
                features.join(" or ")
            ))
        }
    }
}
