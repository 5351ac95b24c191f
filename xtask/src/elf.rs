//! What a firmware image is, read from its ELF: the board it was built for (the symbol
//! `NAV440_BOARD`) and whether every loadable byte lies where that board's chip has memory.
//!
//! The chips' memories are the boards' descriptions (`boards/src/description.rs`, crate
//! `nav440-boards`: the chips' whole flash and RAM as their reference manuals give them, which
//! the crate's tests hold as literals), not the memory maps generated from them: the check
//! is what catches a map that puts an image where its chip has no memory.

use nav440_boards::Board;
use object::{Object, ObjectSection, ObjectSymbol, SectionFlags};
use std::path::Path;

/// The board named `name` (the image's `NAV440_BOARD`).
pub fn chip(name: &str) -> Result<&'static Board, String> {
    nav440_boards::find(name).map_err(|e| format!("{e} in the image"))
}

fn read(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

fn parse<'a>(path: &Path, data: &'a [u8]) -> Result<object::File<'a>, String> {
    object::File::parse(data).map_err(|e| format!("{} is not an ELF file: {e}", path.display()))
}

/// The board name the image carries (`NAV440_BOARD`, NUL-terminated), `None` if it has none
/// (e.g. the bench binary).
pub fn board_of(path: &Path) -> Result<Option<String>, String> {
    let data = read(path)?;
    let elf = parse(path, &data)?;
    board_in(&elf)
}

fn board_in(elf: &object::File<'_>) -> Result<Option<String>, String> {
    let Some(sym) = elf.symbols().find(|s| s.name() == Ok("NAV440_BOARD")) else {
        return Ok(None);
    };
    let section = sym
        .section_index()
        .and_then(|i| elf.section_by_index(i).ok())
        .ok_or("NAV440_BOARD is in no section")?;
    let bytes = section
        .data_range(sym.address(), sym.size())
        .map_err(|e| format!("cannot read NAV440_BOARD: {e}"))?
        .ok_or("NAV440_BOARD lies outside its section's data")?;
    let name = bytes.split(|&b| b == 0).next().unwrap_or_default();
    Ok(Some(String::from_utf8_lossy(name).into_owned()))
}

/// What the memory-map check found in one image.
#[derive(Debug)]
pub struct MapReport {
    /// The board the image names.
    pub board: String,
    /// Loadable sections checked.
    pub sections: usize,
    /// Address of `.vector_table`.
    pub vector_table: u64,
    /// Symbols of `core::fmt`'s float formatting the image links (none expected).
    pub float_symbols: Vec<String>,
}

/// Checks `path` against its board's chip: the image names its board (and it is `expect`
/// when given); every allocated section lies inside the chip's flash or RAM (by its run-time
/// address), every loadable segment's load address with file bytes inside flash, and
/// `.vector_table` starts at the chip's boot address; where the description gives the linker
/// less of a memory than the chip has (`link_kib`), the sections in it and the load ranges lie
/// inside that part. The error names the section or segment and its addresses. The report lists the float formatting symbols the image links.
pub fn check_memory_map(path: &Path, expect: Option<&str>) -> Result<MapReport, String> {
    let data = read(path)?;
    let elf = parse(path, &data)?;
    let shown = path.display();
    let board = board_in(&elf)?
        .ok_or_else(|| format!("{shown}: the image names no board (no NAV440_BOARD symbol)"))?;
    if let Some(want) = expect {
        if board != want {
            return Err(format!(
                "{shown}: the image is built for board `{board}`, expected `{want}`"
            ));
        }
    }
    check_sections(path, &elf, chip(&board)?)
}

/// Checks `path` against the chip of board `board`, whether or not the image names a board:
/// for an image built outside this workspace (the outside-firmware fixture), which carries no
/// `NAV440_BOARD`. The same checks as [`check_memory_map`].
pub fn check_memory_map_for(path: &Path, board: &str) -> Result<MapReport, String> {
    let data = read(path)?;
    let elf = parse(path, &data)?;
    check_sections(path, &elf, chip(board)?)
}

/// The checks of [`check_memory_map`] against `chip`.
fn check_sections(
    path: &Path,
    elf: &object::File<'_>,
    chip: &'static Board,
) -> Result<MapReport, String> {
    let shown = path.display();
    let board = chip.name.to_owned();
    let mut sections = 0;
    let mut vector_table = None;
    for s in elf.sections() {
        let alloc = match s.flags() {
            SectionFlags::Elf { sh_flags } => sh_flags & u64::from(object::elf::SHF_ALLOC) != 0,
            _ => false,
        };
        if !alloc || s.size() == 0 {
            continue;
        }
        let name = s.name().unwrap_or("?");
        let (start, len) = (s.address(), s.size());
        if !chip.flash.contains(start, len) && !chip.ram.contains(start, len) {
            return Err(format!(
                "{shown}: section {name} at {start:#010x}..{:#010x} lies outside {}'s {} ({:#010x}, {} KiB) and {} ({:#010x}, {} KiB)",
                start + len,
                chip.name,
                chip.flash.name,
                chip.flash.origin,
                chip.flash.kib,
                chip.ram.name,
                chip.ram.origin,
                chip.ram.kib
            ));
        }
        for r in [&chip.flash, &chip.ram] {
            if r.link_kib.is_some() && r.contains(start, len) && !r.link_contains(start, len) {
                return Err(over_budget(&shown, "section", name, start, len, chip, r));
            }
        }
        if name == ".vector_table" {
            vector_table = Some(start);
        }
        sections += 1;
    }
    // The load addresses (what a probe writes) are the program headers' `p_paddr`.
    let object::File::Elf32(f) = elf else {
        return Err(format!("{shown}: not a 32-bit ELF file"));
    };
    let e = f.endian();
    for h in f.elf_program_headers() {
        let file_len = u64::from(h.p_filesz.get(e));
        if h.p_type.get(e) != object::elf::PT_LOAD || file_len == 0 {
            continue;
        }
        let (load, run) = (u64::from(h.p_paddr.get(e)), u64::from(h.p_vaddr.get(e)));
        if !chip.flash.contains(load, file_len) {
            return Err(format!(
                "{shown}: a loadable segment ({file_len} bytes, run address {run:#010x}) is loaded at {load:#010x}..{:#010x}, outside {}'s {} ({:#010x}, {} KiB): a probe cannot write it",
                load + file_len,
                chip.name,
                chip.flash.name,
                chip.flash.origin,
                chip.flash.kib
            ));
        }
        if !chip.flash.link_contains(load, file_len) {
            let what = format!("at run address {run:#010x}");
            return Err(over_budget(
                &shown,
                "loadable segment",
                &what,
                load,
                file_len,
                chip,
                &chip.flash,
            ));
        }
    }
    let vector_table =
        vector_table.ok_or_else(|| format!("{shown}: the image has no .vector_table section"))?;
    if vector_table != chip.vector_table() {
        return Err(format!(
            "{shown}: section .vector_table is at {vector_table:#010x}, but {} boots from {:#010x}",
            chip.name,
            chip.vector_table()
        ));
    }
    Ok(MapReport {
        board,
        sections,
        vector_table,
        float_symbols: float_symbols_in(elf),
    })
}

/// The error for `len` bytes at `start` (a section or a segment's load range) inside the
/// chip's region `r` but past the part of it the board's description gives the linker
/// (`link_kib`: the budget of a smaller part the image must fit).
fn over_budget(
    shown: &std::path::Display<'_>,
    kind: &str,
    name: &str,
    start: u64,
    len: u64,
    chip: &Board,
    r: &nav440_boards::Region,
) -> String {
    format!(
        "{shown}: {kind} {name} at {start:#010x}..{:#010x} ends {} bytes past the {} KiB of {}'s {} its description gives the linker (link_kib)",
        start + len,
        (start + len).saturating_sub(r.origin + r.link_length()),
        r.link_length() >> 10,
        chip.name,
        r.name
    )
}

/// Parts of the (mangled) symbol names of `core::fmt`'s float formatting (`Display`, `Debug`
/// and `LowerExp` of `f32`/`f64` all go through `core::fmt::float` and `core::num::flt2dec`).
const FLOAT_FMT: &[&str] = &[
    "flt2dec",
    "float_to_decimal",
    "float_to_exponential",
    "3fmt5float",
];

/// The symbols of `elf` that belong to `core::fmt`'s float formatting (none expected in a
/// firmware image: it sends raw bits and the host formats them).
fn float_symbols_in(elf: &object::File<'_>) -> Vec<String> {
    symbols_with(elf, FLOAT_FMT)
}

/// The (mangled) names of the symbols of `elf` that contain one of `parts`.
fn symbols_with(elf: &object::File<'_>, parts: &[&str]) -> Vec<String> {
    elf.symbols()
        .filter_map(|s| s.name().ok())
        .filter(|n| parts.iter().any(|f| n.contains(f)))
        .map(str::to_owned)
        .collect()
}

/// The (mangled) names of the symbols of the ELF at `path` that contain one of `parts`.
pub fn symbols_containing(path: &Path, parts: &[&str]) -> Result<Vec<String>, String> {
    let data = read(path)?;
    Ok(symbols_with(&parse(path, &data)?, parts))
}

/// Little-endian `u32` at `at`.
fn u32_at(data: &[u8], at: usize) -> Result<u32, String> {
    data.get(at..at + 4)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or_else(|| format!("ELF too short for a word at {at:#x}"))
}

/// Little-endian `u16` at `at`.
fn u16_at(data: &[u8], at: usize) -> Result<usize, String> {
    data.get(at..at + 2)
        .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]])))
        .ok_or_else(|| format!("ELF too short for a half-word at {at:#x}"))
}

fn put_u32(data: &mut [u8], at: usize, v: u32) -> Result<(), String> {
    data.get_mut(at..at + 4)
        .ok_or_else(|| format!("ELF too short for a word at {at:#x}"))?
        .copy_from_slice(&v.to_le_bytes());
    Ok(())
}

/// A copy of the 32-bit little-endian ELF `data` with section `name`'s address (`sh_addr`)
/// set to `addr`: a wrongly linked image, for testing the check.
pub fn with_section_address(data: &[u8], name: &str, addr: u32) -> Result<Vec<u8>, String> {
    let elf = object::File::parse(data).map_err(|e| e.to_string())?;
    let index = elf
        .section_by_name(name)
        .ok_or_else(|| format!("no section {name}"))?
        .index()
        .0;
    // ELF32 header: e_shoff at 0x20, e_shentsize at 0x2E; Elf32_Shdr: sh_addr at +12.
    let shoff = u32_at(data, 0x20)? as usize;
    let shentsize = u16_at(data, 0x2E)?;
    let mut out = data.to_vec();
    put_u32(&mut out, shoff + index * shentsize + 12, addr)?;
    Ok(out)
}

/// A copy of the 32-bit little-endian ELF `data` with the first loadable segment that has file
/// bytes loaded at `addr` (`p_paddr`): an image a probe would write elsewhere, for testing.
pub fn with_load_address(data: &[u8], addr: u32) -> Result<Vec<u8>, String> {
    // ELF32 header: e_phoff at 0x1C, e_phentsize at 0x2A, e_phnum at 0x2C; Elf32_Phdr: p_type
    // +0 (PT_LOAD = 1), p_paddr +12, p_filesz +16.
    let phoff = u32_at(data, 0x1C)? as usize;
    let phentsize = u16_at(data, 0x2A)?;
    let phnum = u16_at(data, 0x2C)?;
    let mut out = data.to_vec();
    for i in 0..phnum {
        let h = phoff + i * phentsize;
        if u32_at(data, h)? == 1 && u32_at(data, h + 16)? > 0 {
            put_u32(&mut out, h + 12, addr)?;
            return Ok(out);
        }
    }
    Err("no loadable segment with file bytes".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// This test program formats a float, so the detector must find the formatting code in
    /// its own executable (a host ELF, same symbol names).
    #[test]
    fn float_formatting_is_found_where_it_is_linked() {
        let text = format!("{}", std::hint::black_box(1.5f64));
        assert_eq!(text, "1.5");
        let exe = std::env::current_exe().expect("test executable");
        let data = read(&exe).expect("readable");
        let found = float_symbols_in(&parse(&exe, &data).expect("an ELF file"));
        assert!(!found.is_empty(), "no float formatting symbol found");
    }
}
