//! What the report needs from a firmware ELF file, read with the `object` crate: the bytes written to
//! flash, the static RAM, and whether the bench's measured symbols are present.

use std::path::Path;

use object::elf::{SHF_ALLOC, SHF_WRITE, SHT_NOBITS};
use object::read::elf::{ElfFile32, SectionHeader};
use object::{Endianness, Object, ObjectSymbol};

/// The sizes of one firmware image, from its section headers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImageSizes {
    /// Bytes written to flash: every allocated section with contents (vector table, text, rodata, and the
    /// initial values of .data).
    pub flash_bytes: u64,
    /// Static RAM: every allocated writable section (.data, .bss, .uninit).
    pub static_ram_bytes: u64,
}

impl ImageSizes {
    /// Sizes of the ELF image in `bytes`.
    pub fn parse(bytes: &[u8]) -> Result<Self, String> {
        let file = ElfFile32::<Endianness>::parse(bytes).map_err(|e| format!("not a 32-bit ELF file: {e}"))?;
        let endian = file.endian();
        let (mut flash_bytes, mut static_ram_bytes) = (0, 0);
        for header in file.elf_section_table().iter() {
            let (ty, flags, size) = (header.sh_type(endian), header.sh_flags(endian), header.sh_size(endian));
            if flags & SHF_ALLOC == 0 {
                continue;
            }
            if ty != SHT_NOBITS {
                flash_bytes += u64::from(size);
            }
            if flags & SHF_WRITE != 0 {
                static_ram_bytes += u64::from(size);
            }
        }
        Ok(Self { flash_bytes, static_ram_bytes })
    }

    /// Sizes of the ELF file at `path`.
    pub fn read(path: &Path) -> Result<Self, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }
}

/// The names in `wanted` that the symbol table of the ELF file at `path` lacks.
pub fn missing_symbols(path: &Path, wanted: &[&str]) -> Result<Vec<String>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let file = ElfFile32::<Endianness>::parse(&*bytes)
        .map_err(|e| format!("{}: not a 32-bit ELF file: {e}", path.display()))?;
    let present: std::collections::BTreeSet<&str> = file.symbols().filter_map(|s| s.name().ok()).collect();
    Ok(wanted.iter().filter(|w| !present.contains(**w)).map(|w| (*w).to_string()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal ELF32 little-endian file: a null section, .text (alloc + exec, 100 bytes), .data (alloc +
    /// write, 8 bytes), .bss (alloc + write, no bits, 40 bytes) and .shstrtab.
    fn tiny_elf() -> Vec<u8> {
        let names = b"\0.text\0.data\0.bss\0.shstrtab\0";
        let shoff = 52 + names.len().next_multiple_of(4);
        let mut b = vec![0u8; 52];
        b[..7].copy_from_slice(b"\x7fELF\x01\x01\x01");
        b[0x10..0x12].copy_from_slice(&2u16.to_le_bytes()); // executable
        b[0x12..0x14].copy_from_slice(&40u16.to_le_bytes()); // EM_ARM
        b[0x14..0x18].copy_from_slice(&1u32.to_le_bytes());
        b[0x20..0x24].copy_from_slice(&(shoff as u32).to_le_bytes());
        b[0x28..0x2A].copy_from_slice(&52u16.to_le_bytes());
        b[0x2E..0x30].copy_from_slice(&40u16.to_le_bytes());
        b[0x30..0x32].copy_from_slice(&5u16.to_le_bytes());
        b[0x32..0x34].copy_from_slice(&4u16.to_le_bytes());
        b.extend_from_slice(names);
        b.resize(shoff, 0);
        let mut header = |name: u32, ty: u32, flags: u32, offset: u32, size: u32| {
            for v in [name, ty, flags, 0, offset, size, 0, 0, 4, 0] {
                b.extend_from_slice(&v.to_le_bytes());
            }
        };
        header(0, 0, 0, 0, 0);
        header(1, 1, SHF_ALLOC | 0x4, 0, 0);
        header(7, 1, SHF_ALLOC | SHF_WRITE, 0, 8);
        header(13, SHT_NOBITS, SHF_ALLOC | SHF_WRITE, 0, 40);
        header(18, 3, 0, 52, names.len() as u32);
        // .text is 100 bytes with its contents at offset 0 (the header itself: only sizes are read).
        let text = shoff + 40 + 20;
        b[text..text + 4].copy_from_slice(&100u32.to_le_bytes());
        b
    }

    #[test]
    fn sections_give_flash_and_static_ram() {
        let sizes = ImageSizes::parse(&tiny_elf()).unwrap();
        assert_eq!(sizes, ImageSizes { flash_bytes: 108, static_ram_bytes: 48 });
    }

    #[test]
    fn other_input_is_an_error() {
        assert!(ImageSizes::parse(b"not an elf").is_err());
        let mut truncated = tiny_elf();
        truncated.truncate(120);
        assert!(ImageSizes::parse(&truncated).is_err());
    }
}
