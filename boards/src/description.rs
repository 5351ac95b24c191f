//! The boards the firmware is built for: one [`Board`] each.
//!
//! Memories are the chips', from their reference manuals and data sheets (the tests of this
//! crate hold the same figures as literals): `kib` is what the chip has, `link_kib` what the
//! memory map gives the linker when that is less.

use super::{Board, BootLoader, Image, Region, Twin, Uart};

/// Every board; [`crate::validate`] checks the list on every firmware build.
pub const BOARDS: &[Board] = &[
    Board {
        name: "mps2",
        part: "QEMU mps2-an385/an386 (ARM AN385/AN386: 4 MiB code SSRAM at 0, 4 MiB SSRAM at 0x2000_0000)",
        default: true,
        example: true,
        backend: None,
        targets: &[
            "thumbv7em-none-eabihf",
            "thumbv7m-none-eabi",
            "thumbv6m-none-eabi",
        ],
        probe_chip: None,
        qemu: &["mps2-an386", "mps2-an385"],
        embassy_feature: None,
        uart: Uart {
            peripheral: "UART0 (CMSDK APB UART, IRQ 0)",
            tx: None,
            rx: None,
            function: None,
        },
        // The map is sized to an STM32F405-class part (1 MiB flash, 128 KiB SRAM): an image
        // that fits here fits there.
        flash: Region {
            name: "code memory",
            origin: 0,
            kib: 4096,
            link_kib: Some(1024),
        },
        ram: Region {
            name: "SRAM",
            origin: 0x2000_0000,
            kib: 4096,
            link_kib: Some(128),
        },
        boot_loader: None,
        ci_image: Image::PAPER,
    },
    Board {
        name: "stm32f405",
        part: "STM32F405RG (RM0090: 1 MiB flash at 0x0800_0000, SRAM1+SRAM2 128 KiB at 0x2000_0000)",
        default: false,
        example: true,
        backend: Some("stm32f4_hal"),
        targets: &["thumbv7em-none-eabihf"],
        probe_chip: Some("STM32F405RGTx"),
        qemu: &["netduinoplus2"],
        embassy_feature: Some("stm32f405"),
        uart: Uart {
            peripheral: "USART1",
            tx: Some("PA9"),
            rx: Some("PA10"),
            function: Some("AF7"),
        },
        // Boot from flash aliases it at 0; the 64 KiB CCM RAM at 0x1000_0000 is not used.
        flash: Region {
            name: "flash",
            origin: 0x0800_0000,
            kib: 1024,
            link_kib: None,
        },
        ram: Region {
            name: "SRAM1+SRAM2",
            origin: 0x2000_0000,
            kib: 128,
            link_kib: None,
        },
        boot_loader: None,
        ci_image: Image::PAPER,
    },
    Board {
        name: "nucleo-f411re",
        part: "STM32F411RE (RM0383: 512 KiB flash at 0x0800_0000, 128 KiB SRAM at 0x2000_0000)",
        default: false,
        example: true,
        backend: Some("stm32f4_hal"),
        targets: &["thumbv7em-none-eabihf"],
        probe_chip: Some("STM32F411RETx"),
        qemu: &[],
        embassy_feature: Some("stm32f411"),
        uart: Uart {
            peripheral: "USART1",
            tx: Some("PA9 (D8)"),
            rx: Some("PA10 (D2)"),
            function: Some("AF7"),
        },
        flash: Region {
            name: "flash",
            origin: 0x0800_0000,
            kib: 512,
            link_kib: None,
        },
        ram: Region {
            name: "SRAM",
            origin: 0x2000_0000,
            kib: 128,
            link_kib: None,
        },
        boot_loader: None,
        ci_image: Image::PAPER,
    },
    Board {
        name: "b-l475e-iot01a",
        part: "STM32L475VG on the B-L475E-IOT01A Discovery kit (RM0351: 1 MiB flash at 0x0800_0000, SRAM1 96 KiB at 0x2000_0000)",
        default: false,
        example: false,
        backend: None,
        targets: &["thumbv7em-none-eabihf"],
        probe_chip: Some("STM32L475VGTx"),
        qemu: &["b-l475e-iot01a"],
        embassy_feature: Some("stm32l475"),
        uart: Uart {
            peripheral: "USART1 (the ST-LINK virtual COM port)",
            tx: Some("PB6"),
            rx: Some("PB7"),
            function: Some("AF7"),
        },
        flash: Region {
            name: "flash",
            origin: 0x0800_0000,
            kib: 1024,
            link_kib: None,
        },
        // SRAM2 (32 KiB at 0x1000_0000, also aliased at 0x2001_8000) is not used.
        ram: Region {
            name: "SRAM1",
            origin: 0x2000_0000,
            kib: 96,
            link_kib: None,
        },
        boot_loader: None,
        ci_image: Image::PAPER,
    },
    Board {
        name: "nucleo-g031k8",
        part: "STM32G031K8 on the NUCLEO-G031K8 (RM0444: 64 KiB flash at 0x0800_0000, 8 KiB SRAM at 0x2000_0000)",
        default: false,
        example: true,
        backend: None,
        targets: &["thumbv6m-none-eabi"],
        probe_chip: Some("STM32G031K8Tx"),
        qemu: &[],
        embassy_feature: None,
        uart: Uart {
            peripheral: "USART1",
            tx: Some("PB6 (D1)"),
            rx: Some("PB7 (D0)"),
            function: Some("AF0"),
        },
        // A board one can buy, for a part one would ship: the K8 has 64 KiB of flash, the
        // linker gets 32 KiB, the flash of the STM32G031K6 (same family, package and 8 KiB of
        // SRAM, DS12992). An image that links here, and passes the map check (the ELF against
        // the K8's 64 KiB and against the 32 KiB budget), fits a 32 KiB / 8 KiB part.
        flash: Region {
            name: "flash",
            origin: 0x0800_0000,
            kib: 64,
            link_kib: Some(32),
        },
        ram: Region {
            name: "SRAM",
            origin: 0x2000_0000,
            kib: 8,
            link_kib: None,
        },
        boot_loader: None,
        // The image the small part is for: the product bank without the Euler reference,
        // profile `small`. The paper bank's can never fit 32 KiB. No emulator runs the
        // STM32G031: its stack is measured on the same image for the emulated Cortex-M0
        // (docs/PORTING.md).
        ci_image: Image {
            features: &["fixed-gains", "no-reference"],
            profile: "small",
            in_ci: true,
            stack_twin: Some(Twin {
                qemu_board: "an385-v6m",
                features: &["small-part"],
            }),
        },
    },
    Board {
        name: "rp-pico",
        part: "RP2040 on the Raspberry Pi Pico (2 MiB QSPI flash at 0x1000_0000, 264 KiB SRAM at 0x2000_0000; boot2 in the first 256 bytes)",
        default: false,
        example: true,
        backend: None,
        targets: &["thumbv6m-none-eabi"],
        probe_chip: Some("RP2040"),
        qemu: &[],
        embassy_feature: None,
        uart: Uart {
            peripheral: "UART0",
            tx: Some("GP0"),
            rx: Some("GP1"),
            function: Some("UART"),
        },
        // The Pico's flash, executed in place; the boot ROM runs the second-stage boot loader
        // (from the rp2040-boot2 crate) at its start, which starts the image whose vector table
        // follows it.
        flash: Region {
            name: "flash (XIP)",
            origin: 0x1000_0000,
            kib: 2048,
            link_kib: None,
        },
        // SRAM0-3 (256 KiB, striped); the 4 KiB banks SRAM4/5 are not used.
        ram: Region {
            name: "SRAM",
            origin: 0x2000_0000,
            kib: 264,
            link_kib: Some(256),
        },
        boot_loader: Some(BootLoader {
            bytes: 256,
            section: ".boot2",
            symbol: "BOOT2_FIRMWARE",
        }),
        ci_image: Image::PAPER,
    },
];
