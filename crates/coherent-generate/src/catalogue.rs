//! What scenes are made of: kinds of rooms, furniture and objects with real dimensions
//! (metres: width along x, height, depth along z), what opens and closes, what a
//! quadrotor lands on, and where each is found.
//!
//! The sizes follow the robots' specs (`coherent_core::geometry::RobotSpecs`, the
//! defaults every generated file writes out):
//!
//! - the legged robot's hand reaches 1.34 m, and a surface is out of its reach under the
//!   `geometric` rules when its top plus the tallest movable thing is above that
//!   (`docs/task-format.md`, "Geometric rules"). Every movable thing here is at most
//!   [`MAX_THING`] high and the tallest kinds are drawn into every scene, so the
//!   counters the fixed arms stand on (1.25 m) and the shelves (1.5 m) are high, and
//!   tables, beds, desks and cabinets (at most 1.0 m) are low;
//! - every movable thing fits the quadrotor's basket with another beside it (at most
//!   [`MAX_FOOTPRINT`] each way, the basket 0.40 m square inside its walls, 0.20 m under
//!   the craft's hub), so whatever a plan loads into the basket fits there physically;
//! - the quadrotor lands on floors and on the counters the fixed arms stand on (2.0 x
//!   1.2 m, at least its landing pad, 1.0 m, each way), not on low tables: a legged
//!   robot that walks up to a table with a quadrotor on it is next to the craft by the
//!   rules, and stays so when it flies away, where physics cannot follow; and on a
//!   table it might stand too far from the basket to reach it;
//! - movable things stand steady: no taller than twice their narrowest side;
//! - nothing in a room is taller than 1.7 m: the quadrotor cruises at 1.9 m;
//! - the counters a fixed arm stands on are 2.0 x 1.2 m, with the arm at the back and
//!   its right metre kept free as the quadrotor's landing pad (as in the project's own
//!   benchmark, `benchmark/README.md`).

use coherent_core::geometry::Lid;

/// The most a movable thing measures along x or z (m).
pub const MAX_FOOTPRINT: f32 = 0.16;
/// The most a movable thing measures up (m).
pub const MAX_THING: f32 = 0.16;

/// Which wall of its room a piece of furniture stands against. Front-opening and
/// lidded containers open towards the room's middle only from the back wall (their
/// doors open towards -z), so they stand there; other things stand at either.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wall {
    /// The wall at the room's largest z.
    Back,
    /// Either the back or the front wall (the smallest z).
    Either,
}

/// A kind of furniture.
#[derive(Clone, Copy, Debug)]
pub struct FurnitureKind {
    pub name: &'static str,
    /// The graph's `category`.
    pub category: &'static str,
    /// Width (x), height, depth (z).
    pub size: [f32; 3],
    pub surface: bool,
    pub container: bool,
    /// How it opens: a container with a lid or door starts closed or open (`CAN_OPEN`).
    pub lid: Lid,
    pub landable: bool,
    /// A counter a fixed arm stands on.
    pub arm: bool,
    pub wall: Wall,
}

/// A kind of movable thing.
#[derive(Clone, Copy, Debug)]
pub struct ThingKind {
    pub name: &'static str,
    pub category: &'static str,
    pub size: [f32; 3],
    /// An open container (a bowl, a tray): small things go in it.
    pub container: bool,
    /// The rooms it belongs to, by kind name: where a scene puts it, and where a task's
    /// start puts it most often.
    pub rooms: &'static [&'static str],
}

/// A kind of room.
#[derive(Clone, Copy, Debug)]
pub struct RoomKind {
    pub name: &'static str,
    /// Width (x) and depth (z), least and most.
    pub width: (f32, f32),
    pub depth: (f32, f32),
    /// The furniture it may have, by kind name, the first ones most likely.
    pub furniture: &'static [&'static str],
    /// Whether a room of a second storey may be of this kind.
    pub upstairs: bool,
}

const fn piece(name: &'static str, size: [f32; 3], wall: Wall) -> FurnitureKind {
    FurnitureKind {
        name,
        category: "Furniture",
        size,
        surface: true,
        container: false,
        lid: Lid::None,
        landable: false,
        arm: false,
        wall,
    }
}

const fn counter(name: &'static str) -> FurnitureKind {
    FurnitureKind {
        landable: true,
        arm: true,
        ..piece(name, COUNTER, Wall::Back)
    }
}

/// A cupboard that opens at the front. Its top is no surface: the legged robot would
/// stand beside what is on it, and reach the door's handle no more; and it is wider than
/// deep, so that the legged robot works on it from the front, where the handle is.
const fn cupboard(name: &'static str, size: [f32; 3]) -> FurnitureKind {
    FurnitureKind {
        surface: false,
        container: true,
        lid: Lid::Front,
        ..piece(name, size, Wall::Back)
    }
}

/// A box with a lid on top (not a surface: its lid is in the way).
const fn chest(name: &'static str, size: [f32; 3]) -> FurnitureKind {
    FurnitureKind {
        surface: false,
        container: true,
        lid: Lid::Top,
        ..piece(name, size, Wall::Back)
    }
}

/// An open container standing on the floor.
const fn bin(name: &'static str, size: [f32; 3]) -> FurnitureKind {
    FurnitureKind {
        surface: false,
        container: true,
        ..piece(name, size, Wall::Either)
    }
}

/// The counter a fixed arm stands on: high for the legged robot, 2.0 x 1.2 m.
pub const COUNTER: [f32; 3] = [2.0, 1.25, 1.2];

/// Every kind of furniture.
pub const FURNITURE: &[FurnitureKind] = &[
    counter("kitchen counter"),
    counter("bar counter"),
    counter("workbench"),
    counter("packing bench"),
    counter("folding counter"),
    FurnitureKind {
        category: "Appliances",
        ..cupboard("fridge", [0.8, 1.7, 0.7])
    },
    cupboard("kitchen cabinet", [0.8, 0.9, 0.6]),
    cupboard("sideboard", [1.6, 0.9, 0.5]),
    cupboard("dresser", [1.0, 0.8, 0.5]),
    cupboard("wardrobe", [1.0, 1.7, 0.6]),
    cupboard("filing cabinet", [0.8, 1.0, 0.5]),
    cupboard("shoe cabinet", [0.8, 0.9, 0.5]),
    cupboard("tool cabinet", [0.8, 1.0, 0.5]),
    cupboard("bathroom cabinet", [0.8, 0.85, 0.5]),
    chest("storage box", [0.6, 0.45, 0.5]),
    chest("toy chest", [0.8, 0.5, 0.5]),
    chest("cardboard box", [0.6, 0.45, 0.5]),
    bin("laundry basket", [0.5, 0.5, 0.5]),
    bin("crate", [0.6, 0.4, 0.5]),
    bin("recycling bin", [0.5, 0.6, 0.4]),
    piece("dining table", [1.4, 0.75, 1.0], Wall::Either),
    piece("coffee table", [1.2, 0.45, 1.0], Wall::Either),
    // Not landable: a craft landed at the far side of a bed is out of the legged
    // robot's reach from the near side.
    piece("bed", [1.8, 0.55, 1.6], Wall::Back),
    piece("play table", [1.2, 0.5, 1.0], Wall::Either),
    piece("pallet", [1.4, 0.15, 1.0], Wall::Either),
    piece("garden table", [1.4, 0.75, 1.0], Wall::Either),
    piece("sofa", [2.0, 0.45, 0.8], Wall::Either),
    piece("tv stand", [1.4, 0.5, 0.5], Wall::Back),
    piece("nightstand", [0.7, 0.55, 0.5], Wall::Either),
    piece("side table", [0.7, 0.55, 0.5], Wall::Either),
    piece("desk", [1.4, 0.75, 0.7], Wall::Either),
    piece("vanity", [1.2, 0.85, 0.6], Wall::Back),
    piece("console table", [1.0, 0.8, 0.4], Wall::Back),
    piece("bookshelf", [1.0, 1.5, 0.4], Wall::Back),
    piece("pantry shelf", [1.0, 1.5, 0.4], Wall::Back),
    piece("wall shelf", [0.8, 1.5, 0.3], Wall::Back),
    piece("storage rack", [1.2, 1.5, 0.5], Wall::Back),
    piece("display cabinet", [1.0, 1.5, 0.4], Wall::Back),
];

/// Every kind of room.
pub const ROOMS: &[RoomKind] = &[
    RoomKind {
        name: "kitchen",
        width: (5.0, 7.0),
        depth: (5.0, 6.0),
        furniture: &[
            "kitchen counter",
            "fridge",
            "dining table",
            "kitchen cabinet",
            "pantry shelf",
            "recycling bin",
        ],
        upstairs: false,
    },
    RoomKind {
        name: "living room",
        width: (5.5, 8.0),
        depth: (5.0, 6.0),
        furniture: &[
            "coffee table",
            "sofa",
            "bookshelf",
            "tv stand",
            "storage box",
            "side table",
        ],
        upstairs: true,
    },
    RoomKind {
        name: "bedroom",
        width: (5.0, 7.0),
        depth: (5.0, 6.0),
        furniture: &["bed", "wardrobe", "nightstand", "dresser", "wall shelf"],
        upstairs: true,
    },
    RoomKind {
        name: "bathroom",
        width: (4.5, 6.0),
        depth: (5.0, 5.5),
        furniture: &["vanity", "laundry basket", "bathroom cabinet", "wall shelf"],
        upstairs: true,
    },
    RoomKind {
        name: "dining room",
        width: (5.0, 7.0),
        depth: (5.0, 6.0),
        furniture: &[
            "dining table",
            "bar counter",
            "sideboard",
            "display cabinet",
        ],
        upstairs: false,
    },
    RoomKind {
        name: "study",
        width: (4.5, 6.5),
        depth: (5.0, 5.5),
        furniture: &["desk", "filing cabinet", "bookshelf", "side table"],
        upstairs: true,
    },
    RoomKind {
        name: "hall",
        width: (4.5, 7.0),
        depth: (5.0, 5.5),
        furniture: &["console table", "shoe cabinet", "wall shelf"],
        upstairs: false,
    },
    RoomKind {
        name: "storage room",
        width: (5.0, 7.0),
        depth: (5.0, 6.0),
        furniture: &[
            "packing bench",
            "pallet",
            "storage rack",
            "cardboard box",
            "crate",
        ],
        upstairs: false,
    },
    RoomKind {
        name: "workshop",
        width: (5.0, 7.0),
        depth: (5.0, 6.0),
        furniture: &["workbench", "tool cabinet", "storage rack", "crate"],
        upstairs: false,
    },
    RoomKind {
        name: "laundry room",
        width: (4.5, 6.0),
        depth: (5.0, 5.5),
        furniture: &[
            "folding counter",
            "laundry basket",
            "wall shelf",
            "recycling bin",
        ],
        upstairs: true,
    },
    RoomKind {
        name: "kids room",
        width: (5.0, 6.5),
        depth: (5.0, 6.0),
        furniture: &["play table", "toy chest", "bed", "wall shelf"],
        upstairs: true,
    },
    RoomKind {
        name: "conservatory",
        width: (5.0, 8.0),
        depth: (5.0, 6.0),
        furniture: &["garden table", "storage box", "crate"],
        upstairs: false,
    },
];

const KITCHEN: &[&str] = &["kitchen", "dining room"];
const LIVING: &[&str] = &["living room", "study", "hall"];

/// Every kind of movable thing.
pub const THINGS: &[ThingKind] = &[
    thing("mug", "Tableware", [0.09, 0.10, 0.09], KITCHEN),
    thing("cup", "Tableware", [0.08, 0.10, 0.08], KITCHEN),
    thing("apple", "Fruit", [0.08, 0.08, 0.08], KITCHEN),
    thing("orange", "Fruit", [0.08, 0.08, 0.08], KITCHEN),
    thing("banana", "Fruit", [0.16, 0.04, 0.06], KITCHEN),
    thing("lemon", "Fruit", [0.07, 0.07, 0.07], KITCHEN),
    thing("butter", "Food", [0.10, 0.05, 0.07], KITCHEN),
    thing("jam jar", "Food", [0.08, 0.12, 0.08], KITCHEN),
    thing("yogurt", "Food", [0.07, 0.08, 0.07], KITCHEN),
    thing("salt shaker", "Tableware", [0.06, 0.10, 0.06], KITCHEN),
    thing(
        "pepper mill",
        "Tableware",
        [0.07, 0.14, 0.07],
        &["kitchen", "dining room"],
    ),
    thing(
        "wine glass",
        "Tableware",
        [0.08, 0.16, 0.08],
        &["dining room", "kitchen"],
    ),
    thing("napkins", "Tableware", [0.15, 0.03, 0.15], &["dining room"]),
    open("small bowl", "Tableware", [0.16, 0.07, 0.16], KITCHEN),
    open(
        "fruit bowl",
        "Tableware",
        [0.16, 0.06, 0.16],
        &["dining room", "kitchen"],
    ),
    thing(
        "remote control",
        "Electronics",
        [0.05, 0.03, 0.16],
        &["living room"],
    ),
    thing("paperback", "Books", [0.11, 0.03, 0.16], LIVING),
    thing(
        "candle",
        "Decor",
        [0.07, 0.12, 0.07],
        &["living room", "dining room"],
    ),
    thing("coaster", "Decor", [0.10, 0.02, 0.10], &["living room"]),
    thing(
        "game controller",
        "Electronics",
        [0.15, 0.05, 0.10],
        &["living room", "kids room"],
    ),
    thing(
        "phone",
        "Electronics",
        [0.08, 0.02, 0.16],
        &["bedroom", "living room"],
    ),
    thing(
        "alarm clock",
        "Electronics",
        [0.12, 0.10, 0.07],
        &["bedroom"],
    ),
    thing(
        "glasses case",
        "Accessories",
        [0.16, 0.04, 0.06],
        &["bedroom", "study"],
    ),
    thing(
        "socks",
        "Clothes",
        [0.14, 0.04, 0.10],
        &["bedroom", "laundry room"],
    ),
    thing(
        "wallet",
        "Accessories",
        [0.11, 0.02, 0.09],
        &["bedroom", "hall"],
    ),
    thing("soap", "Bathroom", [0.09, 0.04, 0.06], &["bathroom"]),
    thing("toothbrush", "Bathroom", [0.16, 0.02, 0.03], &["bathroom"]),
    thing("shampoo", "Bathroom", [0.08, 0.14, 0.07], &["bathroom"]),
    thing(
        "sponge",
        "Bathroom",
        [0.12, 0.04, 0.08],
        &["bathroom", "kitchen"],
    ),
    thing("comb", "Bathroom", [0.16, 0.02, 0.04], &["bathroom"]),
    thing("notebook", "Books", [0.15, 0.02, 0.16], &["study"]),
    thing("stapler", "Office", [0.15, 0.06, 0.05], &["study"]),
    thing(
        "tape",
        "Office",
        [0.10, 0.05, 0.10],
        &["study", "storage room"],
    ),
    thing("calculator", "Office", [0.08, 0.02, 0.15], &["study"]),
    thing(
        "pencil case",
        "Office",
        [0.16, 0.05, 0.07],
        &["study", "kids room"],
    ),
    thing(
        "headphones",
        "Electronics",
        [0.16, 0.08, 0.14],
        &["study", "living room"],
    ),
    thing("screwdriver", "Tools", [0.16, 0.03, 0.03], &["workshop"]),
    thing(
        "tape measure",
        "Tools",
        [0.07, 0.07, 0.04],
        &["workshop", "storage room"],
    ),
    thing(
        "light bulb",
        "Tools",
        [0.07, 0.11, 0.07],
        &["storage room", "workshop"],
    ),
    thing(
        "paint can",
        "Tools",
        [0.12, 0.14, 0.12],
        &["workshop", "storage room"],
    ),
    thing("glue", "Tools", [0.06, 0.12, 0.06], &["workshop"]),
    thing(
        "work gloves",
        "Tools",
        [0.15, 0.03, 0.10],
        &["workshop", "conservatory"],
    ),
    thing(
        "battery pack",
        "Tools",
        [0.10, 0.05, 0.07],
        &["storage room", "workshop"],
    ),
    open(
        "parts tray",
        "Tools",
        [0.16, 0.05, 0.12],
        &["workshop", "storage room"],
    ),
    thing(
        "rubber duck",
        "Toys",
        [0.10, 0.10, 0.10],
        &["kids room", "bathroom"],
    ),
    thing(
        "teddy bear",
        "Toys",
        [0.14, 0.16, 0.12],
        &["kids room", "bedroom"],
    ),
    thing("toy car", "Toys", [0.15, 0.08, 0.08], &["kids room"]),
    thing(
        "ball",
        "Toys",
        [0.10, 0.10, 0.10],
        &["kids room", "conservatory"],
    ),
    open("block box", "Toys", [0.16, 0.10, 0.16], &["kids room"]),
    thing(
        "keys",
        "Accessories",
        [0.08, 0.02, 0.05],
        &["hall", "living room"],
    ),
    thing("scarf", "Clothes", [0.16, 0.04, 0.12], &["hall", "bedroom"]),
    thing(
        "detergent",
        "Cleaning",
        [0.10, 0.16, 0.08],
        &["laundry room"],
    ),
    thing(
        "clothes pegs",
        "Cleaning",
        [0.10, 0.05, 0.08],
        &["laundry room"],
    ),
    thing(
        "towel",
        "Bathroom",
        [0.16, 0.06, 0.12],
        &["bathroom", "laundry room"],
    ),
    thing(
        "flower pot",
        "Plants",
        [0.12, 0.14, 0.12],
        &["conservatory", "living room"],
    ),
    thing(
        "watering can",
        "Tools",
        [0.16, 0.16, 0.10],
        &["conservatory"],
    ),
    thing(
        "sunglasses",
        "Accessories",
        [0.14, 0.04, 0.05],
        &["conservatory", "hall"],
    ),
];

const fn thing(
    name: &'static str,
    category: &'static str,
    size: [f32; 3],
    rooms: &'static [&'static str],
) -> ThingKind {
    ThingKind {
        name,
        category,
        size,
        container: false,
        rooms,
    }
}

const fn open(
    name: &'static str,
    category: &'static str,
    size: [f32; 3],
    rooms: &'static [&'static str],
) -> ThingKind {
    ThingKind {
        container: true,
        ..thing(name, category, size, rooms)
    }
}

/// The furniture kind of that name.
pub fn furniture(name: &str) -> Option<&'static FurnitureKind> {
    FURNITURE.iter().find(|f| f.name == name)
}

/// The room kind of that name.
pub fn room(name: &str) -> Option<&'static RoomKind> {
    ROOMS
        .iter()
        .chain([&LANDING, &STAIR_HALL])
        .find(|r| r.name == name)
}

/// The room a flight of stairs arrives in, upstairs (never drawn otherwise).
pub const LANDING: RoomKind = RoomKind {
    name: "landing",
    width: (4.5, 6.0),
    depth: (5.0, 5.5),
    furniture: &["console table", "wall shelf", "side table"],
    upstairs: true,
};

/// The room a flight of stairs leaves from, downstairs.
pub const STAIR_HALL: RoomKind = RoomKind {
    name: "stair hall",
    width: (5.0, 6.5),
    depth: (7.0, 7.5),
    furniture: &["console table", "shoe cabinet", "side table"],
    upstairs: false,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_resolves_and_every_size_keeps_the_rules() {
        for r in ROOMS.iter().chain([&LANDING, &STAIR_HALL]) {
            for f in r.furniture {
                assert!(furniture(f).is_some(), "{}: no furniture {f}", r.name);
            }
        }
        for t in THINGS {
            assert!(
                t.size[0] <= MAX_FOOTPRINT && t.size[2] <= MAX_FOOTPRINT,
                "{}",
                t.name
            );
            assert!(t.size[1] <= MAX_THING, "{}", t.name);
            for r in t.rooms {
                assert!(room(r).is_some(), "{}: no room {r}", t.name);
            }
        }
        for f in FURNITURE {
            assert!(
                f.size[1] <= 1.7,
                "{} is taller than the quadrotor's clearance",
                f.name
            );
            if f.landable {
                assert!(
                    f.arm && f.size[0] >= 1.0 && f.size[2] >= 1.0,
                    "{}: landable",
                    f.name
                );
            }
            if f.container && f.lid != Lid::None {
                assert!(f.size[0] >= f.size[2], "{} is deeper than wide", f.name);
            }
            if f.surface && !f.arm && f.size[1] < 1.2 {
                assert!(
                    f.size[1] <= 0.9,
                    "{}: a low top above 0.9 m strains the legged robot's arm",
                    f.name
                );
            }
        }
        for t in THINGS {
            assert!(
                t.size[1] >= 0.02,
                "{}: too thin for a put spot's probe to see",
                t.name
            );
            let narrow = t.size[0].min(t.size[2]);
            assert!(t.size[1] <= 2.0 * narrow + 1e-6, "{}: tips over", t.name);
        }
        let names: Vec<&str> = THINGS.iter().map(|t| t.name).collect();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[..i].contains(n), "{n} twice");
        }
    }
}
