//! Stack frames of a Cortex-M0/M0+ image (`thumbv6m-none-eabi`), read from its ELF: each
//! function's prologue, decoded from its first instructions (ARMv6-M, ARM DDI 0419):
//!
//! * `PUSH {registers}` (`0xB400 | M << 8 | list`): 4 bytes per register, LR included (`M`);
//! * `SUB SP, SP, #imm7 * 4` (`0xB080 | imm7`);
//! * a larger frame: `LDR Rt, [PC, #imm8 * 4]` (`0x4800 | Rt << 8 | imm8`), whose literal is a
//!   negative size, then `ADD SP, SP, Rt` (`0x4485 | Rt << 3`).
//!
//! Compared between a board's image and its emulated twin (`nav440_boards::Twin`), the frames
//! bound what the board's own code may add to the stack the twin's runs measured.

use object::{Object, ObjectSection, ObjectSymbol, SymbolKind};
use std::collections::HashMap;
use std::path::Path;

/// Instructions of a prologue read at most (the frame is set up before any call).
const PROLOGUE: usize = 12;

/// Each function's frame in the ELF at `path`, bytes, by its mangled name without the hash
/// (`17h<16 hex digits>E` at the end), so that the same function in two images has one key;
/// the largest where several functions share a key.
pub fn thumb_frames(path: &Path) -> Result<HashMap<String, u64>, String> {
    let data = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let elf = object::File::parse(&*data)
        .map_err(|e| format!("{} is not an ELF file: {e}", path.display()))?;
    let mut frames = HashMap::new();
    for sym in elf
        .symbols()
        .filter(|s| s.kind() == SymbolKind::Text && s.size() >= 2)
    {
        let Some(section) = sym
            .section_index()
            .and_then(|i| elf.section_by_index(i).ok())
        else {
            continue;
        };
        let (Ok(bytes), Ok(name)) = (section.data(), sym.name()) else {
            continue;
        };
        // The Thumb bit is not part of the address.
        let start = (sym.address() & !1).saturating_sub(section.address());
        let frame = prologue_frame(bytes, start as usize, section.address());
        let slot = frames.entry(without_hash(name).to_owned()).or_insert(0);
        *slot = frame.max(*slot);
    }
    Ok(frames)
}

/// `name` without the legacy mangling's hash (`...17h0123456789abcdefE` -> `...`).
fn without_hash(name: &str) -> &str {
    let b = name.as_bytes();
    let n = b.len();
    let hashed = n > 20
        && name.ends_with('E')
        && name.get(n - 20..n - 17) == Some("17h")
        && b[n - 17..n - 1].iter().all(u8::is_ascii_hexdigit);
    if hashed {
        &name[..n - 20]
    } else {
        name
    }
}

/// The frame the prologue at `start` of `text` (a section at address `base`) sets up, bytes.
fn prologue_frame(text: &[u8], start: usize, base: u64) -> u64 {
    let half = |at: usize| {
        text.get(at..at + 2)
            .map(|h| u16::from_le_bytes([h[0], h[1]]))
    };
    let word = |at: usize| {
        text.get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
    };
    let mut frame = 0u64;
    // Literals loaded by `LDR Rt, [PC, #imm]`, per register.
    let mut literal: [Option<u32>; 8] = [None; 8];
    let mut at = start;
    for _ in 0..PROLOGUE {
        let Some(op) = half(at) else { break };
        if op & 0xFE00 == 0xB400 {
            frame += 4 * u64::from((op & 0x01FF).count_ones());
        } else if op & 0xFF80 == 0xB080 {
            frame += 4 * u64::from(op & 0x7F);
        } else if op & 0xF800 == 0x4800 {
            // PC is the instruction's address + 4, aligned down to 4.
            let pc = (base as usize + at + 4) & !3;
            let lit = pc + 4 * usize::from(op & 0xFF);
            let reg = usize::from((op >> 8) & 7);
            literal[reg] = lit.checked_sub(base as usize).and_then(word);
        } else if op & 0xFF87 == 0x4485 {
            let reg = usize::from((op >> 3) & 0xF);
            if let Some(Some(v)) = literal.get(reg) {
                // A negative size added to SP.
                frame += u64::from(v.wrapping_neg());
            }
        } else if op & 0xF800 == 0xF000 {
            // A 32-bit instruction (BL): the prologue is over.
            break;
        }
        at += 2;
    }
    frame
}

/// What `board`'s frames may add to its twin's stack: for every function in both, how much
/// larger the board's frame is (none when smaller), plus every frame of the board's own
/// functions, which the twin does not have. The largest terms come with it, for the message.
pub fn excess_over(
    board: &HashMap<String, u64>,
    twin: &HashMap<String, u64>,
) -> (u64, Vec<(u64, String)>) {
    let mut terms: Vec<(u64, String)> = board
        .iter()
        .filter_map(|(name, &b)| {
            let extra = twin.get(name).map_or(b, |&t| b.saturating_sub(t));
            (extra > 0).then(|| (extra, name.clone()))
        })
        .collect();
    terms.sort_unstable_by(|a, b| b.cmp(a));
    (terms.iter().map(|(n, _)| n).sum(), terms)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Prologues assembled by hand from the ARMv6-M encodings: `push {r4-r7, lr}` (20 B) and
    /// `sub sp, #0x1a4` (420 B); `push {r7, lr}`, `ldr r6, [pc, #4]`, `add sp, r6` with the
    /// literal -1,744 (1,752 B).
    #[test]
    fn frames_from_hand_assembled_prologues() {
        let small = [0xF0, 0xB5, 0xE9, 0xB0, 0x00, 0xBF];
        assert_eq!(prologue_frame(&small, 0, 0), 20 + 0x69 * 4);
        let mut big = vec![0x80, 0xB5, 0x01, 0x4E, 0xB5, 0x44, 0x00, 0xBF];
        big.extend_from_slice(&(-1744i32).to_le_bytes());
        // The literal: PC = (2 + 4) & !3 = 4, + 4 * 1 = 8.
        assert_eq!(prologue_frame(&big, 0, 0x0800_0000), 8 + 1744);
    }

    #[test]
    fn the_hash_goes_the_name_stays() {
        assert_eq!(
            without_hash("_ZN16firmware_example9configure17h3cee85d439a64eb2E"),
            "_ZN16firmware_example9configure"
        );
        assert_eq!(without_hash("memcpy"), "memcpy");
    }

    #[test]
    fn the_excess_counts_larger_and_own_frames_only() {
        let board = HashMap::from([
            ("a".to_owned(), 100),
            ("b".to_owned(), 40),
            ("c".to_owned(), 8),
        ]);
        let twin = HashMap::from([("a".to_owned(), 90), ("b".to_owned(), 56)]);
        let (sum, terms) = excess_over(&board, &twin);
        assert_eq!(sum, 18);
        assert_eq!(terms, vec![(10, "a".to_owned()), (8, "c".to_owned())]);
    }
}
