//! The tags a scene names its parts by — `generator` and constraint `type` — each an enum with its one list of names. Parsing turns the string into the enum
//! and then matches it exhaustively, so adding a tag here makes the compiler list every place
//! that has to handle it.

macro_rules! tags {
    ($(#[$meta:meta])* $name:ident { $($(#[$vmeta:meta])* $variant:ident = $text:literal),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name {
            $($(#[$vmeta])* $variant),+
        }

        impl $name {
            /// Every tag, in the order of [`Self::NAMES`].
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
            /// The names as written in a scene file.
            pub const NAMES: &'static [&'static str] = &[$($text),+];

            /// The name as written in a scene file.
            pub fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $text),+
                }
            }

            /// The tag of a name, if it is one.
            pub fn from_name(name: &str) -> Option<Self> {
                match name {
                    $($text => Some($name::$variant),)+
                    _ => None,
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

tags! {
    /// `[mesh] generator = "…"`.
    Generator {
        /// A flat disc.
        Disc = "disc",
        /// A geodesic sphere.
        Icosphere = "icosphere",
        /// The part of a sphere above a horizontal cut.
        TruncatedSphere = "truncated-sphere",
        /// A mesh file.
        File = "file",
        /// A meridian of quadratic elements: the axisymmetric model (docs/theory.md §15).
        Axisymmetric = "axisymmetric",
    }
}

impl Generator {
    /// The `[mesh]` keys of this generator, besides `generator`.
    pub fn options(self) -> &'static [&'static str] {
        match self {
            Generator::Disc => &["radius", "sectors", "divisions", "group"],
            Generator::Icosphere => &["radius", "frequency", "down"],
            Generator::TruncatedSphere => &["radius", "cut-height", "pattern", "divisions"],
            Generator::File => &["path", "group"],
            Generator::Axisymmetric => &["shape", "radius", "cut-height", "elements", "modes"],
        }
    }

    /// The key of the mesh resolution (`divisions`, an icosphere's `frequency`), if any.
    pub fn resolution_key(self) -> Option<&'static str> {
        match self {
            Generator::Disc | Generator::TruncatedSphere => Some("divisions"),
            Generator::Icosphere => Some("frequency"),
            Generator::Axisymmetric => Some("elements"),
            Generator::File => None,
        }
    }
}

tags! {
    /// `[[constraint]] type = "…"`.
    ConstraintKind {
        /// A fixed fluid volume.
        FluidVolume = "fluid-volume",
        /// A fixed amount of gas.
        GasAmount = "gas-amount",
        /// A parameter held at its start value.
        Fixed = "fixed",
    }
}
