//! Per-element tables for atoms drawn as spheres: van der Waals radii and CPK colours.
//!
//! **Radii** (Å): A. Bondi, "van der Waals Volumes and Radii", *J. Phys. Chem.* 68 (1964) 441–451,
//! for the elements Bondi lists; the main-group elements he does not list are taken from
//! M. Mantina et al., "Consistent van der Waals Radii for the Whole Main Group",
//! *J. Phys. Chem. A* 113 (2009) 5806–5812 (marked `M` below). Elements in neither (most
//! transition metals, lanthanides) get [`FALLBACK_RADIUS`] and the loader says so in a warning.
//! PyMOL uses the same Bondi values for C, N, O, S (1.70, 1.55, 1.52, 1.80).
//!
//! **Colours**: Jmol's CPK element colours (<https://jmol.sourceforge.net/jscolors/>), given there
//! as 8-bit sRGB; [`element_color`] converts them to linear RGB, the colour space of the scene.

/// Radius (Å) for an element that neither Bondi (1964) nor Mantina et al. (2009) lists.
pub const FALLBACK_RADIUS: f64 = 2.0;

/// Jmol's colour for an unknown element (deep pink), 8-bit sRGB.
const FALLBACK_COLOR_SRGB8: u32 = 0xFF1493;

/// (symbol, van der Waals radius in Å if tabulated, Jmol CPK colour as 0xRRGGBB sRGB).
const ELEMENTS: &[(&str, Option<f64>, u32)] = &[
    ("H", Some(1.20), 0xFFFFFF),
    ("D", Some(1.20), 0xFFFFC0), // deuterium: H's radius, Jmol's deuterium colour
    ("He", Some(1.40), 0xD9FFFF),
    ("Li", Some(1.82), 0xCC80FF),
    ("Be", Some(1.53), 0xC2FF00), // M
    ("B", Some(1.92), 0xFFB5B5),  // M
    ("C", Some(1.70), 0x909090),
    ("N", Some(1.55), 0x3050F8),
    ("O", Some(1.52), 0xFF0D0D),
    ("F", Some(1.47), 0x90E050),
    ("Ne", Some(1.54), 0xB3E3F5),
    ("Na", Some(2.27), 0xAB5CF2),
    ("Mg", Some(1.73), 0x8AFF00),
    ("Al", Some(1.84), 0xBFA6A6), // M
    ("Si", Some(2.10), 0xF0C8A0),
    ("P", Some(1.80), 0xFF8000),
    ("S", Some(1.80), 0xFFFF30),
    ("Cl", Some(1.75), 0x1FF01F),
    ("Ar", Some(1.88), 0x80D1E3),
    ("K", Some(2.75), 0x8F40D4),
    ("Ca", Some(2.31), 0x3DFF00), // M
    ("Sc", None, 0xE6E6E6),
    ("Ti", None, 0xBFC2C7),
    ("V", None, 0xA6A6AB),
    ("Cr", None, 0x8A99C7),
    ("Mn", None, 0x9C7AC7),
    ("Fe", None, 0xE06633),
    ("Co", None, 0xF090A0),
    ("Ni", Some(1.63), 0x50D050),
    ("Cu", Some(1.40), 0xC88033),
    ("Zn", Some(1.39), 0x7D80B0),
    ("Ga", Some(1.87), 0xC28F8F),
    ("Ge", Some(2.11), 0x668F8F), // M
    ("As", Some(1.85), 0xBD80E3),
    ("Se", Some(1.90), 0xFFA100),
    ("Br", Some(1.85), 0xA62929),
    ("Kr", Some(2.02), 0x5CB8D1),
    ("Rb", Some(3.03), 0x702EB0), // M
    ("Sr", Some(2.49), 0x00FF00), // M
    ("Y", None, 0x94FFFF),
    ("Zr", None, 0x94E0E0),
    ("Nb", None, 0x73C2C9),
    ("Mo", None, 0x54B5B5),
    ("Tc", None, 0x3B9E9E),
    ("Ru", None, 0x248F8F),
    ("Rh", None, 0x0A7D8C),
    ("Pd", Some(1.63), 0x006985),
    ("Ag", Some(1.72), 0xC0C0C0),
    ("Cd", Some(1.58), 0xFFD98F),
    ("In", Some(1.93), 0xA67573),
    ("Sn", Some(2.17), 0x668080),
    ("Sb", Some(2.06), 0x9E63B5), // M
    ("Te", Some(2.06), 0xD47A00),
    ("I", Some(1.98), 0x940094),
    ("Xe", Some(2.16), 0x429EB0),
    ("Cs", Some(3.43), 0x57178F), // M
    ("Ba", Some(2.68), 0x00C900), // M
    ("La", None, 0x70D4FF),
    ("Ce", None, 0xFFFFC7),
    ("Pr", None, 0xD9FFC7),
    ("Nd", None, 0xC7FFC7),
    ("Sm", None, 0x8FFFC7),
    ("Eu", None, 0x61FFC7),
    ("Gd", None, 0x45FFC7),
    ("Tb", None, 0x30FFC7),
    ("Dy", None, 0x1FFFC7),
    ("Ho", None, 0x00FF9C),
    ("Er", None, 0x00E675),
    ("Tm", None, 0x00D452),
    ("Yb", None, 0x00BF38),
    ("Lu", None, 0x00AB24),
    ("Hf", None, 0x4DC2FF),
    ("Ta", None, 0x4DA6FF),
    ("W", None, 0x2194D6),
    ("Re", None, 0x267DAB),
    ("Os", None, 0x266696),
    ("Ir", None, 0x175487),
    ("Pt", Some(1.72), 0xD0D0E0),
    ("Au", Some(1.66), 0xFFD123),
    ("Hg", Some(1.55), 0xB8B8D0),
    ("Tl", Some(1.96), 0xA6544D),
    ("Pb", Some(2.02), 0x575961),
    ("Bi", Some(2.07), 0x9E4FB5), // M
    ("Po", Some(1.97), 0xAB5C00), // M
    ("At", Some(2.02), 0x754F45), // M
    ("Rn", Some(2.20), 0x428296), // M
    ("Fr", Some(3.48), 0x420066), // M
    ("Ra", Some(2.83), 0x007D00), // M
    ("U", Some(1.86), 0x008FFF),
];

/// An element as found in a structure file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Element {
    index: usize,
}

impl Element {
    /// Looks a symbol up, ignoring case and surrounding blanks (`" FE"`, `"Fe"`, `"fe"`).
    pub fn from_symbol(symbol: &str) -> Option<Element> {
        let s = symbol.trim();
        ELEMENTS
            .iter()
            .position(|(sym, _, _)| sym.eq_ignore_ascii_case(s))
            .map(|index| Element { index })
    }

    /// The symbol, capitalised as usual (`"Fe"`).
    pub fn symbol(self) -> &'static str {
        ELEMENTS.get(self.index).map_or("?", |e| e.0)
    }

    /// The van der Waals radius in Å, if one of the cited tables has it.
    pub fn vdw_radius(self) -> Option<f64> {
        ELEMENTS.get(self.index).and_then(|e| e.1)
    }

    /// Hydrogen or deuterium.
    pub fn is_hydrogen(self) -> bool {
        matches!(self.symbol(), "H" | "D")
    }

    /// Jmol's CPK colour, linear RGB.
    pub fn color(self) -> glam::DVec3 {
        srgb8_hex_to_linear(
            ELEMENTS
                .get(self.index)
                .map_or(FALLBACK_COLOR_SRGB8, |e| e.2),
        )
    }
}

/// The CPK colour of an element, or Jmol's colour for an unknown one, linear RGB.
pub fn element_color(element: Option<Element>) -> glam::DVec3 {
    element.map_or_else(|| srgb8_hex_to_linear(FALLBACK_COLOR_SRGB8), Element::color)
}

/// The radius of an element in Å ([`FALLBACK_RADIUS`] where none is tabulated).
pub fn element_radius(element: Option<Element>) -> f64 {
    element
        .and_then(Element::vdw_radius)
        .unwrap_or(FALLBACK_RADIUS)
}

/// 0xRRGGBB (8-bit sRGB) to linear RGB ([`crate::color::srgb_to_linear`]).
pub fn srgb8_hex_to_linear(hex: u32) -> glam::DVec3 {
    let ch = |shift: u32| crate::color::srgb_to_linear(f64::from((hex >> shift) & 0xFF) / 255.0);
    glam::DVec3::new(ch(16), ch(8), ch(0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookup_is_case_insensitive_and_trims() {
        assert_eq!(Element::from_symbol(" FE").map(Element::symbol), Some("Fe"));
        assert_eq!(Element::from_symbol("c").map(Element::symbol), Some("C"));
        assert!(Element::from_symbol("Xx").is_none());
        assert!(Element::from_symbol("").is_none());
    }

    #[test]
    fn bondi_values() {
        let r = |s: &str| Element::from_symbol(s).and_then(Element::vdw_radius);
        assert_eq!(r("C"), Some(1.70));
        assert_eq!(r("N"), Some(1.55));
        assert_eq!(r("O"), Some(1.52));
        assert_eq!(r("S"), Some(1.80));
        assert_eq!(r("H"), Some(1.20));
        assert_eq!(r("Fe"), None);
        assert_eq!(element_radius(Element::from_symbol("Fe")), FALLBACK_RADIUS);
    }

    #[test]
    fn srgb_decoding() {
        // 0x90 = 144: (144/255 + 0.055)/1.055)^2.4 ≈ 0.2789
        let c = Element::from_symbol("C")
            .map(Element::color)
            .unwrap_or_default();
        assert!((c.x - 0.278894).abs() < 1e-5, "{c}");
        assert_eq!(c.x, c.y);
    }
}
