//! Scene env0 (bedroom 0, childroom 2, livingroom 4, kitchen 6; door 8 between bedroom
//! and livingroom starts CLOSED, doors 9 and 10 are OPEN_FOREVER).
//!
//! Every expected list below was derived by hand from `env0.json` and docs/semantics.md:
//! section 2 for observations, section 3 for action lists, section 4 for transitions.
//!
//! The tests start from openings built once (`common`): a task's initial state, or the
//! state that a story of another test ends in. A story that ends where an opening begins
//! checks that it got there (`expect_state_of`), so the opening's moves and the story's
//! cannot drift apart.

mod common;

use std::sync::LazyLock;

use coherent_core::Reason;
use common::{Move, Scene, with};

// Robots of env0.
const QUAD: i64 = 22;
const DOG: i64 = 23;
const ARM: i64 = 24; // on the dining table (13) of the livingroom
const ARM_BEDROOM: i64 = 50; // on the high table (33) of the bedroom

/// Task 16, livingroom (4): everything INSIDE it (floor 5, the dog, the arm, the
/// quadrotor), then what is ON/INSIDE those: sofa 11, coffee table 12, dining table 13,
/// basket 25 (ON the floor); microwave 15, plate 51 (ON 13); knife 54 (ON 12). The bread
/// 26 is INSIDE the CLOSED microwave: hidden. Plus doors 8, 9, 10 and the four rooms.
const LIVINGROOM_16: &[i64] = &[
    0, 2, 4, 5, 6, 8, 9, 10, 11, 12, 13, 15, 22, 23, 24, 25, 51, 54,
];

/// `LIVINGROOM_16` and the bread 26, once the microwave is open or the bread is in the
/// plate on the table.
const LIVINGROOM_16_AND_BREAD: &[i64] = &[
    0, 2, 4, 5, 6, 8, 9, 10, 11, 12, 13, 15, 22, 23, 24, 25, 26, 51, 54,
];

/// Task 16, the edges between the nodes of `LIVINGROOM_16` at the start.
const LIVINGROOM_16_EDGES: &[(i64, &str, i64)] = &[
    (5, "INSIDE", 4),
    (8, "LEADING TO", 0),
    (8, "LEADING TO", 4),
    (9, "LEADING TO", 2),
    (9, "LEADING TO", 4),
    (10, "LEADING TO", 4),
    (10, "LEADING TO", 6),
    (11, "ON", 5),
    (12, "ON", 5),
    (13, "ON", 5),
    (15, "ON", 13),
    (22, "ON", 5),
    (22, "INSIDE", 4),
    (22, "WITH", 25),
    (23, "ON", 5),
    (23, "INSIDE", 4),
    (24, "ON", 13),
    (24, "INSIDE", 4),
    (25, "ON", 5),
    (51, "ON", 13),
    (54, "ON", 12),
];

/// Task 16, the dog in the livingroom with nothing CLOSE. Unreached: doors 8, 9, 10,
/// sofa 11, coffee table 12, basket 25, knife 54 (dining table 13 is HIGH_HEIGHT,
/// microwave 15 and plate 51 are ON_HIGH_SURFACE). Door 8 is CLOSED: no bedroom.
const DOG_LIVINGROOM_16: &[&str] = &[
    "[movetowards] <door>(8)",
    "[movetowards] <door>(9)",
    "[movetowards] <door>(10)",
    "[movetowards] <sofa>(11)",
    "[movetowards] <coffee table>(12)",
    "[movetowards] <basket>(25)",
    "[movetowards] <knife>(54)",
    "[movetowards] <childroom>(2)",
    "[movetowards] <kitchen>(6)",
];

/// Task 16, the dog in the kitchen with nothing CLOSE and the fridge CLOSED.
const DOG_KITCHEN_16: &[&str] = &[
    "[movetowards] <door>(10)",
    "[movetowards] <fridge>(14)",
    "[movetowards] <kitchen table>(32)",
    "[movetowards] <livingroom>(4)",
];

/// Task 6, the dog in the livingroom with nothing CLOSE: the hat 20 is ON the coffee
/// table; the basket is in the bedroom with the quadrotor.
const DOG_LIVINGROOM_6: &[&str] = &[
    "[movetowards] <door>(8)",
    "[movetowards] <door>(9)",
    "[movetowards] <door>(10)",
    "[movetowards] <sofa>(11)",
    "[movetowards] <coffee table>(12)",
    "[movetowards] <hat>(20)",
    "[movetowards] <childroom>(2)",
    "[movetowards] <kitchen>(6)",
];

// The moves the openings below are made of.

/// The arm takes the bread out of the microwave and puts it into the plate beside it.
const BREAD_INTO_THE_PLATE: &[Move] = &[
    (ARM, "[grab] <bread>(26)"),
    (ARM, "[putinto] <bread>(26) into <plate>(51)"),
];

/// The dog fetches the knife from the coffee table and puts it into the basket.
const KNIFE_INTO_THE_BASKET: &[Move] = &[
    (DOG, "[movetowards] <coffee table>(12)"),
    (DOG, "[grab] <knife>(54)"),
    (DOG, "[movetowards] <basket>(25)"),
    (DOG, "[putinto] <knife>(54) into <basket>(25)"),
];

/// The quadrotor, flying in the livingroom, lands its basket on the arm's table.
const LAND_ON_THE_DINING_TABLE: &[Move] = &[
    (QUAD, "[movetowards] <dining table>(13)"),
    (QUAD, "[land_on] <dining table>(13)"),
];

/// The arm puts the plate into the basket landed beside it; the quadrotor takes off.
const PLATE_INTO_THE_BASKET_AND_OFF: &[Move] = &[
    (ARM, "[grab] <plate>(51)"),
    (ARM, "[putinto] <plate>(51) into <basket>(25)"),
    (QUAD, "[takeoff_from] <dining table>(13)"),
];

/// The quadrotor flies from the livingroom to the kitchen and lands on its floor.
const FLY_TO_THE_KITCHEN_FLOOR: &[Move] = &[
    (QUAD, "[movetowards] <kitchen>(6)"),
    (QUAD, "[land_on] <kitchen floor>(7)"),
];

const TAKE_OFF_IN_THE_LIVINGROOM: Move = (QUAD, "[takeoff_from] <livingroom floor>(5)");

// Openings: the states the tests start from, each built once.

static TASK16: LazyLock<Scene> = LazyLock::new(|| Scene::load("env0", 16));
static MICROWAVE_OPEN: LazyLock<Scene> =
    LazyLock::new(|| TASK16.after("the microwave opened", &[(ARM, "[open] <microwave>(15)")]));
static BREAD_IN_THE_PLATE: LazyLock<Scene> =
    LazyLock::new(|| MICROWAVE_OPEN.after("the bread put into the plate", BREAD_INTO_THE_PLATE));
static QUAD_FLYING: LazyLock<Scene> =
    LazyLock::new(|| TASK16.after("the take-off", &[TAKE_OFF_IN_THE_LIVINGROOM]));
static KNIFE_IN_THE_BASKET: LazyLock<Scene> =
    LazyLock::new(|| TASK16.after("the knife put into the basket", KNIFE_INTO_THE_BASKET));
static KNIFE_FLYING: LazyLock<Scene> =
    LazyLock::new(|| KNIFE_IN_THE_BASKET.after("the take-off", &[TAKE_OFF_IN_THE_LIVINGROOM]));
static KNIFE_ON_THE_DINING_TABLE: LazyLock<Scene> = LazyLock::new(|| {
    KNIFE_FLYING.after("the landing on the dining table", LAND_ON_THE_DINING_TABLE)
});
static PLATE_AND_KNIFE_FLYING: LazyLock<Scene> = LazyLock::new(|| {
    KNIFE_ON_THE_DINING_TABLE.after("the plate loaded", PLATE_INTO_THE_BASKET_AND_OFF)
});
static PLATE_AND_KNIFE_IN_THE_KITCHEN: LazyLock<Scene> = LazyLock::new(|| {
    PLATE_AND_KNIFE_FLYING.after("the flight to the kitchen", FLY_TO_THE_KITCHEN_FLOOR)
});
static DOG_IN_THE_KITCHEN: LazyLock<Scene> =
    LazyLock::new(|| TASK16.after("the dog's walk", &[(DOG, "[movetowards] <kitchen>(6)")]));
static DOG_AT_THE_OPEN_FRIDGE: LazyLock<Scene> = LazyLock::new(|| {
    DOG_IN_THE_KITCHEN.after(
        "the fridge opened",
        &[
            (DOG, "[movetowards] <fridge>(14)"),
            (DOG, "[open] <fridge>(14)"),
        ],
    )
});
static BREAD_IN_THE_PLATE_ON_THE_DINING_TABLE: LazyLock<Scene> = LazyLock::new(|| {
    let flying = BREAD_IN_THE_PLATE.after("the take-off", &[TAKE_OFF_IN_THE_LIVINGROOM]);
    flying.after("the landing on the dining table", LAND_ON_THE_DINING_TABLE)
});
static BREAD_IN_THE_PLATE_IN_THE_BASKET: LazyLock<Scene> = LazyLock::new(|| {
    BREAD_IN_THE_PLATE_ON_THE_DINING_TABLE.after(
        "the plate put into the basket",
        &[
            (ARM, "[grab] <plate>(51)"),
            (ARM, "[putinto] <plate>(51) into <basket>(25)"),
        ],
    )
});
static TASK6: LazyLock<Scene> = LazyLock::new(|| Scene::load("env0", 6));
static BEDROOM_DOOR_OPEN: LazyLock<Scene> = LazyLock::new(|| {
    TASK6.after(
        "the take-off and the door opened",
        &[
            (QUAD, "[takeoff_from] <bedroom floor>(1)"),
            (DOG, "[movetowards] <door>(8)"),
            (DOG, "[open] <door>(8)"),
        ],
    )
});
static BASKET_DOWN_IN_THE_LIVINGROOM_6: LazyLock<Scene> = LazyLock::new(|| {
    BEDROOM_DOOR_OPEN.after(
        "the dog in the bedroom and the basket landed in the livingroom",
        &[
            (DOG, "[movetowards] <bedroom>(0)"),
            (QUAD, "[movetowards] <livingroom>(4)"),
            (QUAD, "[land_on] <livingroom floor>(5)"),
        ],
    )
});

static BREAD_BACK_IN_THE_OPEN_FRIDGE: LazyLock<Scene> = LazyLock::new(|| {
    DOG_AT_THE_OPEN_FRIDGE.after(
        "the bread taken out and put back",
        &[
            (DOG, "[movetowards] <bread>(21)"),
            (DOG, "[grab] <bread>(21)"),
            (DOG, "[putinto] <bread>(21) into <fridge>(14)"),
        ],
    )
});

#[test]
fn task16_starts_with_each_robot_seeing_its_room_and_offered_what_it_reaches() {
    let s = TASK16.clone();
    for robot in [QUAD, DOG, ARM] {
        s.expect_view(robot, LIVINGROOM_16);
        s.expect_edges(robot, LIVINGROOM_16_EDGES);
    }
    // Landed on the livingroom floor: it can only take off.
    s.expect_actions(QUAD, &["[takeoff_from] <livingroom floor>(5)"]);
    // Nothing is CLOSE yet.
    s.expect_actions(DOG, DOG_LIVINGROOM_16);
    // The arm reaches what is ON the dining table: microwave 15 (CLOSED container) and
    // plate 51 (GRABABLE, OPEN_FOREVER container: nothing to open or close).
    s.expect_actions(ARM, &["[open] <microwave>(15)", "[grab] <plate>(51)"]);

    // The other arm, alone in the bedroom on the high table with nothing beside it.
    s.expect_view(ARM_BEDROOM, &[0, 1, 2, 4, 6, 8, 27, 33, 50]);
    s.expect_edges(
        ARM_BEDROOM,
        &[
            (1, "INSIDE", 0),
            (8, "LEADING TO", 0),
            (8, "LEADING TO", 4),
            (27, "ON", 1),
            (33, "ON", 1),
            (50, "ON", 33),
            (50, "INSIDE", 0),
        ],
    );
    s.expect_actions(ARM_BEDROOM, &[]);
}

#[test]
fn opening_the_microwave_replaces_its_states_and_shows_the_bread_to_the_whole_room() {
    let mut s = TASK16.clone();
    s.act(ARM, "[open] <microwave>(15)");
    // The whole state set is replaced: OFF is gone.
    assert_eq!(s.states(15), ["OPEN"]);
    for robot in [QUAD, DOG, ARM] {
        s.expect_view(robot, LIVINGROOM_16_AND_BREAD);
        s.expect_seen_edges(robot, &[(26, "INSIDE", 15)]);
    }
    s.expect_actions(
        ARM,
        &[
            "[close] <microwave>(15)",
            "[grab] <bread>(26)",
            "[grab] <plate>(51)",
        ],
    );
    // The bread is ON_HIGH_SURFACE: the dog's list does not change.
    s.expect_actions(DOG, DOG_LIVINGROOM_16);
    s.expect_state_of(&MICROWAVE_OPEN);
}

#[test]
fn the_arm_takes_the_bread_out_of_the_microwave_and_puts_it_into_the_plate() {
    let mut s = MICROWAVE_OPEN.clone();
    s.act(ARM, "[grab] <bread>(26)");
    s.expect_seen_edges(ARM, &[(24, "HOLD", 26)]);
    s.expect_unseen_edges(ARM, &[(26, "INSIDE", 15)]);
    s.expect_actions(
        ARM,
        &[
            "[puton] <bread>(26) on <dining table>(13)",
            "[putinto] <bread>(26) into <microwave>(15)",
            "[putinto] <bread>(26) into <plate>(51)",
        ],
    );

    let out = s.act(ARM, "[putinto] <bread>(26) into <plate>(51)");
    assert!(!out.done, "the knife is not in the plate yet");
    s.expect_seen_edges(ARM, &[(26, "INSIDE", 51)]);
    s.expect_high(&[26], true);
    s.expect_actions(
        ARM,
        &[
            "[close] <microwave>(15)",
            "[grab] <bread>(26)",
            "[grab] <plate>(51)",
        ],
    );
    s.expect_state_of(&BREAD_IN_THE_PLATE);
}

#[test]
fn a_held_plate_is_seen_only_as_held_and_the_bread_in_it_drops_out_of_view() {
    let mut s = BREAD_IN_THE_PLATE.clone();
    // Holding the plate: the plate has no ON/INSIDE edge any more, so it is visible only
    // as "what A holds", and the bread INSIDE it drops out of view (step 1 of section 2
    // never reaches the plate).
    s.act(ARM, "[grab] <plate>(51)");
    let mut view = LIVINGROOM_16.to_vec();
    view.retain(|&n| n != 51);
    s.expect_view(DOG, &view);
    s.expect_view(ARM, LIVINGROOM_16);
    s.expect_actions(
        ARM,
        &[
            "[puton] <plate>(51) on <dining table>(13)",
            "[putinto] <plate>(51) into <microwave>(15)",
        ],
    );
    s.act(ARM, "[puton] <plate>(51) on <dining table>(13)");
    s.expect_view(DOG, LIVINGROOM_16_AND_BREAD);
    s.expect_seen_edges(DOG, &[(51, "ON", 13), (26, "INSIDE", 51)]);
}

#[test]
fn moving_to_the_coffee_table_brings_the_knife_close_and_the_dog_puts_it_into_the_basket() {
    let mut s = TASK16.clone();

    // The dog fetches the knife from the coffee table: moving to a surface makes what
    // is ON it CLOSE (the floor under the table is not).
    s.act(DOG, "[movetowards] <coffee table>(12)");
    s.expect_seen_edges(DOG, &[(23, "CLOSE", 12), (23, "CLOSE", 54)]);
    s.expect_unseen_edges(DOG, &[(23, "CLOSE", 5)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_16,
            &["[grab] <knife>(54)"],
            &[
                "[movetowards] <coffee table>(12)",
                "[movetowards] <knife>(54)",
            ],
        ),
    );
    s.act(DOG, "[grab] <knife>(54)");
    s.expect_seen_edges(DOG, &[(23, "HOLD", 54), (23, "CLOSE", 12)]);
    s.expect_unseen_edges(DOG, &[(54, "ON", 12), (23, "CLOSE", 54)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_16,
            &["[puton] <knife>(54) on <coffee table>(12)"],
            &[
                "[movetowards] <coffee table>(12)",
                "[movetowards] <knife>(54)",
            ],
        ),
    );
    s.act(DOG, "[movetowards] <basket>(25)");
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_16,
            &["[putinto] <knife>(54) into <basket>(25)"],
            &["[movetowards] <basket>(25)", "[movetowards] <knife>(54)"],
        ),
    );
    s.act(DOG, "[putinto] <knife>(54) into <basket>(25)");
    s.expect_seen_edges(
        DOG,
        &[(54, "INSIDE", 25), (23, "CLOSE", 25), (23, "CLOSE", 54)],
    );
    s.expect_high(&[25, 54], false);
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_16,
            &["[grab] <knife>(54)"],
            &["[movetowards] <basket>(25)", "[movetowards] <knife>(54)"],
        ),
    );
    s.expect_state_of(&KNIFE_IN_THE_BASKET);
}

#[test]
fn taking_off_lifts_the_basket_and_the_knife_in_it_out_of_the_dogs_reach() {
    let mut s = KNIFE_IN_THE_BASKET.clone();
    // Take-off: the basket leaves the floor, the dog's CLOSE edges to the basket and the
    // knife go, and both become ON_HIGH_SURFACE.
    s.act(QUAD, "[takeoff_from] <livingroom floor>(5)");
    assert_eq!(s.states(QUAD), ["FLYING"]);
    s.expect_high(&[25, 54], true);
    s.expect_view(QUAD, LIVINGROOM_16);
    s.expect_seen_edges(
        QUAD,
        &[(22, "ABOVE", 5), (22, "WITH", 25), (54, "INSIDE", 25)],
    );
    s.expect_unseen_edges(
        QUAD,
        &[
            (22, "ON", 5),
            (25, "ON", 5),
            (23, "CLOSE", 25),
            (23, "CLOSE", 54),
        ],
    );
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <livingroom floor>(5)",
            "[movetowards] <dining table>(13)",
            "[movetowards] <childroom>(2)",
            "[movetowards] <kitchen>(6)",
        ],
    );
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_16,
            &[],
            &["[movetowards] <basket>(25)", "[movetowards] <knife>(54)"],
        ),
    );
    s.expect_state_of(&KNIFE_FLYING);
}

#[test]
fn a_basket_landed_on_the_arms_table_is_within_the_arms_reach() {
    let mut s = KNIFE_FLYING.clone();
    // Landing on the (HIGH_HEIGHT) dining table next to the arm.
    s.act(QUAD, "[movetowards] <dining table>(13)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <dining table>(13)",
            "[movetowards] <livingroom floor>(5)",
            "[movetowards] <childroom>(2)",
            "[movetowards] <kitchen>(6)",
        ],
    );
    s.act(QUAD, "[land_on] <dining table>(13)");
    assert_eq!(s.states(QUAD), ["LAND"]);
    s.expect_high(&[25, 54], true);
    s.expect_actions(QUAD, &["[takeoff_from] <dining table>(13)"]);
    s.expect_seen_edges(ARM, &[(22, "ON", 13), (25, "ON", 13), (54, "INSIDE", 25)]);
    s.expect_unseen_edges(ARM, &[(22, "ABOVE", 13)]);
    // The basket is ON the arm's surface, so the arm reaches into it.
    s.expect_actions(
        ARM,
        &[
            "[open] <microwave>(15)",
            "[grab] <plate>(51)",
            "[grab] <knife>(54)",
        ],
    );
    s.expect_state_of(&KNIFE_ON_THE_DINING_TABLE);
}

#[test]
fn the_arm_loads_the_plate_into_the_landed_basket_which_leaves_its_reach_at_take_off() {
    let mut s = KNIFE_ON_THE_DINING_TABLE.clone();
    s.act(ARM, "[grab] <plate>(51)");
    s.expect_actions(
        ARM,
        &[
            "[puton] <plate>(51) on <dining table>(13)",
            "[putinto] <plate>(51) into <basket>(25)",
        ],
    );
    s.act(ARM, "[putinto] <plate>(51) into <basket>(25)");
    s.expect_seen_edges(QUAD, &[(51, "INSIDE", 25), (54, "INSIDE", 25)]);
    s.expect_unseen_edges(QUAD, &[(24, "HOLD", 51), (51, "ON", 13)]);
    s.expect_high(&[51], true);
    s.expect_actions(
        ARM,
        &[
            "[open] <microwave>(15)",
            "[grab] <plate>(51)",
            "[grab] <knife>(54)",
        ],
    );

    // Off again: the basket is no longer ON the dining table, out of the arm's reach.
    s.act(QUAD, "[takeoff_from] <dining table>(13)");
    s.expect_actions(ARM, &["[open] <microwave>(15)"]);
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <dining table>(13)",
            "[movetowards] <livingroom floor>(5)",
            "[movetowards] <childroom>(2)",
            "[movetowards] <kitchen>(6)",
        ],
    );
    s.expect_state_of(&PLATE_AND_KNIFE_FLYING);
}

#[test]
fn the_basket_flies_through_the_open_door_and_lands_low_on_the_kitchen_floor() {
    let mut s = PLATE_AND_KNIFE_FLYING.clone();
    // Into the kitchen through the OPEN_FOREVER door 10: above the kitchen floor.
    s.act(QUAD, "[movetowards] <kitchen>(6)");
    // Kitchen: floor 7, fridge 14, kitchen table 32, high kitchen table 35 (bread 21 is
    // in the CLOSED fridge), door 10, the rooms, the basket and what is in it.
    s.expect_view(QUAD, &[0, 2, 4, 6, 7, 10, 14, 22, 25, 32, 35, 51, 54]);
    s.expect_edges(
        QUAD,
        &[
            (7, "INSIDE", 6),
            (10, "LEADING TO", 4),
            (10, "LEADING TO", 6),
            (14, "ON", 7),
            (22, "ABOVE", 7),
            (22, "INSIDE", 6),
            (22, "WITH", 25),
            (32, "ON", 7),
            (35, "ON", 7),
            (51, "INSIDE", 25),
            (54, "INSIDE", 25),
        ],
    );
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <kitchen floor>(7)",
            "[movetowards] <high kitchen table>(35)",
            "[movetowards] <livingroom>(4)",
        ],
    );
    // The livingroom no longer shows the quadrotor, its basket or what is in it.
    s.expect_view(DOG, &[0, 2, 4, 5, 6, 8, 9, 10, 11, 12, 13, 15, 23, 24]);

    // Landing on the LOW_HEIGHT floor: basket and contents lose ON_HIGH_SURFACE (the
    // plate had it in the file, and loses it too).
    s.act(QUAD, "[land_on] <kitchen floor>(7)");
    s.expect_high(&[25, 51, 54], false);
    s.expect_actions(QUAD, &["[takeoff_from] <kitchen floor>(7)"]);
    s.expect_state_of(&PLATE_AND_KNIFE_IN_THE_KITCHEN);
}

#[test]
fn the_dog_follows_and_moving_to_the_open_basket_brings_what_is_inside_close() {
    let mut s = PLATE_AND_KNIFE_IN_THE_KITCHEN.clone();
    // The dog follows and can now reach the basket and what is in it.
    s.act(DOG, "[movetowards] <kitchen>(6)");
    s.expect_view(DOG, &[0, 2, 4, 6, 7, 10, 14, 22, 23, 25, 32, 35, 51, 54]);
    s.expect_edges(
        DOG,
        &[
            (7, "INSIDE", 6),
            (10, "LEADING TO", 4),
            (10, "LEADING TO", 6),
            (14, "ON", 7),
            (22, "ON", 7),
            (22, "INSIDE", 6),
            (22, "WITH", 25),
            (23, "ON", 7),
            (23, "INSIDE", 6),
            (25, "ON", 7),
            (32, "ON", 7),
            (35, "ON", 7),
            (51, "INSIDE", 25),
            (54, "INSIDE", 25),
        ],
    );
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &[
                "[movetowards] <basket>(25)",
                "[movetowards] <plate>(51)",
                "[movetowards] <knife>(54)",
            ],
            &[],
        ),
    );
    // Moving to the open basket makes everything INSIDE it CLOSE.
    s.act(DOG, "[movetowards] <basket>(25)");
    s.expect_seen_edges(
        DOG,
        &[(23, "CLOSE", 25), (23, "CLOSE", 51), (23, "CLOSE", 54)],
    );
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[grab] <plate>(51)", "[grab] <knife>(54)"],
            &[],
        ),
    );
}

#[test]
fn from_the_kitchen_the_dog_sees_the_closed_fridge_but_not_the_bread_inside() {
    let mut s = TASK16.clone();
    s.act(DOG, "[movetowards] <kitchen>(6)");
    // The quadrotor stayed in the livingroom: its basket is not seen from the kitchen.
    s.expect_view(DOG, &[0, 2, 4, 6, 7, 10, 14, 23, 32, 35]);
    s.expect_edges(
        DOG,
        &[
            (7, "INSIDE", 6),
            (10, "LEADING TO", 4),
            (10, "LEADING TO", 6),
            (14, "ON", 7),
            (23, "ON", 7),
            (23, "INSIDE", 6),
            (32, "ON", 7),
            (35, "ON", 7),
        ],
    );
    s.expect_actions(DOG, DOG_KITCHEN_16);
    s.refused(DOG, "[movetowards] <bread>(21)", Reason::NotInView);
    s.expect_state_of(&DOG_IN_THE_KITCHEN);
}

#[test]
fn the_dog_opens_the_fridge_and_the_bread_inside_comes_into_view() {
    let mut s = DOG_IN_THE_KITCHEN.clone();
    s.act(DOG, "[movetowards] <fridge>(14)");
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[open] <fridge>(14)"],
            &["[movetowards] <fridge>(14)"],
        ),
    );
    s.act(DOG, "[open] <fridge>(14)");
    assert_eq!(s.states(14), ["OPEN"]);
    s.expect_view(DOG, &[0, 2, 4, 6, 7, 10, 14, 21, 23, 32, 35]);
    s.expect_seen_edges(DOG, &[(21, "INSIDE", 14), (23, "CLOSE", 14)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[close] <fridge>(14)", "[movetowards] <bread>(21)"],
            &["[movetowards] <fridge>(14)"],
        ),
    );
    s.expect_state_of(&DOG_AT_THE_OPEN_FRIDGE);
}

#[test]
fn moving_to_an_object_in_an_open_container_brings_the_container_close_too() {
    let mut s = DOG_AT_THE_OPEN_FRIDGE.clone();
    // Moving to an object inside an open container: close to the object and, through
    // its INSIDE edge, to the container.
    s.act(DOG, "[movetowards] <bread>(21)");
    s.expect_seen_edges(DOG, &[(23, "CLOSE", 21), (23, "CLOSE", 14)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[grab] <bread>(21)", "[close] <fridge>(14)"],
            &["[movetowards] <fridge>(14)"],
        ),
    );
    s.act(DOG, "[grab] <bread>(21)");
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[putinto] <bread>(21) into <fridge>(14)"],
            &["[movetowards] <fridge>(14)"],
        ),
    );
    s.refused(DOG, "[close] <fridge>(14)", Reason::HandFull);
    s.act(DOG, "[putinto] <bread>(21) into <fridge>(14)");
    s.expect_seen_edges(
        DOG,
        &[(21, "INSIDE", 14), (23, "CLOSE", 21), (23, "CLOSE", 14)],
    );
    s.expect_state_of(&BREAD_BACK_IN_THE_OPEN_FRIDGE);
}

#[test]
fn a_closed_fridge_hides_the_bread_and_the_dogs_closeness_to_it_until_opened_again() {
    let mut s = BREAD_BACK_IN_THE_OPEN_FRIDGE.clone();
    // Closing the fridge hides the bread; the CLOSE edge to it stays in the state but is
    // not observed, so it gives no action...
    s.act(DOG, "[close] <fridge>(14)");
    assert_eq!(s.states(14), ["CLOSED"]);
    s.expect_view(DOG, &[0, 2, 4, 6, 7, 10, 14, 23, 32, 35]);
    s.expect_unseen_edges(DOG, &[(23, "CLOSE", 21), (21, "INSIDE", 14)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[open] <fridge>(14)"],
            &["[movetowards] <fridge>(14)"],
        ),
    );
    // ...until the fridge is opened again: the bread is then reachable at once.
    s.act(DOG, "[open] <fridge>(14)");
    s.expect_seen_edges(DOG, &[(23, "CLOSE", 21)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[grab] <bread>(21)", "[close] <fridge>(14)"],
            &["[movetowards] <fridge>(14)"],
        ),
    );
    s.act(DOG, "[grab] <bread>(21)");

    s.act(DOG, "[movetowards] <kitchen table>(32)");
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[puton] <bread>(21) on <kitchen table>(32)"],
            &["[movetowards] <kitchen table>(32)"],
        ),
    );
    s.act(DOG, "[puton] <bread>(21) on <kitchen table>(32)");
    s.expect_seen_edges(DOG, &[(21, "ON", 32), (23, "CLOSE", 21), (23, "CLOSE", 32)]);
    s.expect_unseen_edges(DOG, &[(21, "INSIDE", 14), (23, "HOLD", 21)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[grab] <bread>(21)"],
            &["[movetowards] <kitchen table>(32)"],
        ),
    );
}

#[test]
fn the_plate_with_the_bread_goes_into_the_landed_basket_and_all_three_levels_stay_in_view() {
    let mut s = BREAD_IN_THE_PLATE_ON_THE_DINING_TABLE.clone();
    // Three levels: the basket ON the table, (nothing in it yet), the plate ON the table,
    // the bread INSIDE the plate.
    s.expect_actions(
        ARM,
        &[
            "[close] <microwave>(15)",
            "[grab] <bread>(26)",
            "[grab] <plate>(51)",
        ],
    );
    s.act(ARM, "[grab] <plate>(51)");
    s.expect_actions(
        ARM,
        &[
            "[puton] <plate>(51) on <dining table>(13)",
            "[putinto] <plate>(51) into <microwave>(15)",
            "[putinto] <plate>(51) into <basket>(25)",
        ],
    );
    s.act(ARM, "[putinto] <plate>(51) into <basket>(25)");
    // Landed: the basket is ON the table, so step 1 of section 2 reaches the plate in the
    // basket and the bread in the plate.
    s.expect_view(DOG, LIVINGROOM_16_AND_BREAD);
    s.expect_seen_edges(
        DOG,
        &[(25, "ON", 13), (51, "INSIDE", 25), (26, "INSIDE", 51)],
    );
    // The arm reaches the plate in the basket and the bread in the plate.
    s.expect_actions(
        ARM,
        &[
            "[close] <microwave>(15)",
            "[grab] <bread>(26)",
            "[grab] <plate>(51)",
        ],
    );
    s.expect_state_of(&BREAD_IN_THE_PLATE_IN_THE_BASKET);
}

#[test]
fn bread_in_a_plate_in_a_flying_basket_is_out_of_view_until_it_lands_and_the_dog_takes_it() {
    let mut s = BREAD_IN_THE_PLATE_IN_THE_BASKET.clone();
    // Flying, the basket stands on nothing: it and what is INSIDE it are added after the
    // fixpoint (step 3), so the bread INSIDE the plate is not observed.
    s.act(QUAD, "[takeoff_from] <dining table>(13)");
    s.expect_view(DOG, LIVINGROOM_16);
    s.expect_view(QUAD, LIVINGROOM_16);
    s.expect_seen_edges(DOG, &[(51, "INSIDE", 25)]);
    s.expect_actions(ARM, &["[close] <microwave>(15)"]);
    s.act(QUAD, "[movetowards] <kitchen>(6)");
    s.expect_view(QUAD, &[0, 2, 4, 6, 7, 10, 14, 22, 25, 32, 35, 51]);

    // Landed on the kitchen floor the bread is seen again.
    s.act(QUAD, "[land_on] <kitchen floor>(7)");
    s.expect_high(&[25, 51], false);
    s.expect_view(QUAD, &[0, 2, 4, 6, 7, 10, 14, 22, 25, 26, 32, 35, 51]);
    s.expect_seen_edges(
        QUAD,
        &[
            (22, "ON", 7),
            (25, "ON", 7),
            (51, "INSIDE", 25),
            (26, "INSIDE", 51),
        ],
    );

    // The dog moves to the plate: close to the plate, to the bread INSIDE the open
    // plate, and to the basket the plate is INSIDE.
    s.act(DOG, "[movetowards] <kitchen>(6)");
    s.act(DOG, "[movetowards] <plate>(51)");
    s.expect_seen_edges(
        DOG,
        &[(23, "CLOSE", 51), (23, "CLOSE", 26), (23, "CLOSE", 25)],
    );
    s.expect_actions(
        DOG,
        &with(
            DOG_KITCHEN_16,
            &["[grab] <bread>(26)", "[grab] <plate>(51)"],
            &[],
        ),
    );
    s.act(DOG, "[grab] <bread>(26)");
    s.expect_seen_edges(DOG, &[(23, "HOLD", 26)]);
    s.expect_unseen_edges(DOG, &[(26, "INSIDE", 51)]);
}

#[test]
fn a_closed_cabinet_takes_the_knife_on_it_and_in_it_only_once_opened_and_hides_it_when_shut() {
    let mut s = TASK16.clone();
    s.act(DOG, "[movetowards] <knife>(54)");
    // Next to the knife, and to the coffee table it is ON.
    s.expect_seen_edges(DOG, &[(23, "CLOSE", 54), (23, "CLOSE", 12)]);
    s.act(DOG, "[grab] <knife>(54)");
    s.act(DOG, "[movetowards] <childroom>(2)");
    // Childroom: floor 3 with bed 28 and the (CLOSED, empty) cabinet 34; door 9.
    s.expect_view(DOG, &[0, 2, 3, 4, 6, 9, 23, 28, 34, 54]);
    s.expect_edges(
        DOG,
        &[
            (3, "INSIDE", 2),
            (9, "LEADING TO", 2),
            (9, "LEADING TO", 4),
            (23, "ON", 3),
            (23, "INSIDE", 2),
            (23, "HOLD", 54),
            (28, "ON", 3),
            (34, "ON", 3),
        ],
    );
    let childroom: &[&'static str] = &[
        "[movetowards] <door>(9)",
        "[movetowards] <bed>(28)",
        "[movetowards] <cabinet>(34)",
        "[movetowards] <livingroom>(4)",
    ];
    s.expect_actions(DOG, childroom);
    // The cabinet is a CLOSED container and a surface: the knife can go on it, not in it.
    s.act(DOG, "[movetowards] <cabinet>(34)");
    let at_the_cabinet =
        |more: &[&'static str]| with(childroom, more, &["[movetowards] <cabinet>(34)"]);
    s.expect_actions(
        DOG,
        &at_the_cabinet(&["[puton] <knife>(54) on <cabinet>(34)"]),
    );
    s.refused(
        DOG,
        "[putinto] <knife>(54) into <cabinet>(34)",
        Reason::ContainerClosed,
    );
    s.refused(DOG, "[open] <cabinet>(34)", Reason::HandFull);
    s.act(DOG, "[puton] <knife>(54) on <cabinet>(34)");
    s.expect_actions(
        DOG,
        &at_the_cabinet(&["[open] <cabinet>(34)", "[grab] <knife>(54)"]),
    );
    s.act(DOG, "[open] <cabinet>(34)");
    s.expect_actions(
        DOG,
        &at_the_cabinet(&["[close] <cabinet>(34)", "[grab] <knife>(54)"]),
    );
    s.act(DOG, "[grab] <knife>(54)");
    s.expect_actions(
        DOG,
        &at_the_cabinet(&[
            "[putinto] <knife>(54) into <cabinet>(34)",
            "[puton] <knife>(54) on <cabinet>(34)",
        ]),
    );
    s.act(DOG, "[putinto] <knife>(54) into <cabinet>(34)");
    s.expect_seen_edges(
        DOG,
        &[(54, "INSIDE", 34), (23, "CLOSE", 54), (23, "CLOSE", 34)],
    );
    s.expect_actions(
        DOG,
        &at_the_cabinet(&["[close] <cabinet>(34)", "[grab] <knife>(54)"]),
    );
    // Closed in: the knife is hidden.
    s.act(DOG, "[close] <cabinet>(34)");
    s.expect_view(DOG, &[0, 2, 3, 4, 6, 9, 23, 28, 34]);
    s.expect_actions(DOG, &at_the_cabinet(&["[open] <cabinet>(34)"]));
}

/// Task 6: the dog starts in the livingroom, the quadrotor on the bedroom floor, and
/// door 8 between them is CLOSED.
#[test]
fn task6_starts_with_the_quadrotor_and_its_basket_shut_in_the_bedroom() {
    let s = TASK6.clone();
    // Livingroom of task 6: the hat 20 is ON the coffee table, the microwave 15 (ON the
    // dining table) is empty; the quadrotor and its basket are in the bedroom.
    s.expect_view(DOG, &[0, 2, 4, 5, 6, 8, 9, 10, 11, 12, 13, 15, 20, 23, 24]);
    s.expect_edges(
        DOG,
        &[
            (5, "INSIDE", 4),
            (8, "LEADING TO", 0),
            (8, "LEADING TO", 4),
            (9, "LEADING TO", 2),
            (9, "LEADING TO", 4),
            (10, "LEADING TO", 4),
            (10, "LEADING TO", 6),
            (11, "ON", 5),
            (12, "ON", 5),
            (13, "ON", 5),
            (15, "ON", 13),
            (20, "ON", 12),
            (23, "ON", 5),
            (23, "INSIDE", 4),
            (24, "ON", 13),
            (24, "INSIDE", 4),
        ],
    );
    s.expect_actions(DOG, DOG_LIVINGROOM_6);
    s.expect_actions(ARM, &["[open] <microwave>(15)"]);
    // Bedroom: floor 1 with the quadrotor, basket 25, bed 27, high table 33, orange 49;
    // battery 39 and the other arm ON the high table.
    s.expect_view(QUAD, &[0, 1, 2, 4, 6, 8, 22, 25, 27, 33, 39, 49, 50]);
    s.expect_edges(
        QUAD,
        &[
            (1, "INSIDE", 0),
            (8, "LEADING TO", 0),
            (8, "LEADING TO", 4),
            (22, "ON", 1),
            (22, "INSIDE", 0),
            (22, "WITH", 25),
            (25, "ON", 1),
            (27, "ON", 1),
            (33, "ON", 1),
            (39, "ON", 33),
            (49, "ON", 1),
            (50, "ON", 33),
            (50, "INSIDE", 0),
        ],
    );
    s.expect_actions(QUAD, &["[takeoff_from] <bedroom floor>(1)"]);
    s.expect_actions(ARM_BEDROOM, &["[grab] <battery>(39)"]);
}

#[test]
fn a_closed_door_keeps_both_robots_to_their_rooms_until_the_dog_opens_it() {
    let mut s = TASK6.clone();
    // Flying in the closed bedroom: landables are the floor and the high table.
    s.act(QUAD, "[takeoff_from] <bedroom floor>(1)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <bedroom floor>(1)",
            "[movetowards] <high table>(33)",
        ],
    );
    s.refused(QUAD, "[movetowards] <livingroom>(4)", Reason::DoorClosed);
    s.refused(DOG, "[movetowards] <bedroom>(0)", Reason::DoorClosed);

    // The dog goes to the door and opens it.
    s.act(DOG, "[movetowards] <door>(8)");
    s.expect_seen_edges(DOG, &[(23, "CLOSE", 8)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_6,
            &["[open] <door>(8)"],
            &["[movetowards] <door>(8)"],
        ),
    );
    s.refused(ARM, "[open] <door>(8)", Reason::NotOpenable);
    s.act(DOG, "[open] <door>(8)");
    assert_eq!(s.states(8), ["OPEN"]);
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_6,
            &["[close] <door>(8)", "[movetowards] <bedroom>(0)"],
            &["[movetowards] <door>(8)"],
        ),
    );
    // The open door also lets the quadrotor out of the bedroom.
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <bedroom floor>(1)",
            "[movetowards] <high table>(33)",
            "[movetowards] <livingroom>(4)",
        ],
    );
    s.expect_state_of(&BEDROOM_DOOR_OPEN);
}

#[test]
fn through_the_open_door_the_dog_walks_in_under_the_basket_and_the_quadrotor_flies_out() {
    let mut s = BEDROOM_DOOR_OPEN.clone();
    // The dog walks into the bedroom, where the quadrotor hovers over the floor.
    s.act(DOG, "[movetowards] <bedroom>(0)");
    s.expect_view(DOG, &[0, 1, 2, 4, 6, 8, 22, 23, 25, 27, 33, 39, 49, 50]);
    s.expect_edges(
        DOG,
        &[
            (1, "INSIDE", 0),
            (8, "LEADING TO", 0),
            (8, "LEADING TO", 4),
            (22, "ABOVE", 1),
            (22, "INSIDE", 0),
            (22, "WITH", 25),
            (23, "ON", 1),
            (23, "INSIDE", 0),
            (27, "ON", 1),
            (33, "ON", 1),
            (39, "ON", 33),
            (49, "ON", 1),
            (50, "ON", 33),
            (50, "INSIDE", 0),
        ],
    );
    // The basket is ON_HIGH_SURFACE since the take-off; the high table is HIGH_HEIGHT
    // and the battery ON_HIGH_SURFACE.
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <door>(8)",
            "[movetowards] <bed>(27)",
            "[movetowards] <orange>(49)",
            "[movetowards] <livingroom>(4)",
        ],
    );
    s.refused(DOG, "[movetowards] <basket>(25)", Reason::TooHigh);
    s.refused(DOG, "[movetowards] <high table>(33)", Reason::TooHigh);

    // The quadrotor flies out to the livingroom, above its floor.
    s.act(QUAD, "[movetowards] <livingroom>(4)");
    s.expect_view(
        QUAD,
        &[0, 2, 4, 5, 6, 8, 9, 10, 11, 12, 13, 15, 20, 22, 24, 25],
    );
    s.expect_edges(
        QUAD,
        &[
            (5, "INSIDE", 4),
            (8, "LEADING TO", 0),
            (8, "LEADING TO", 4),
            (9, "LEADING TO", 2),
            (9, "LEADING TO", 4),
            (10, "LEADING TO", 4),
            (10, "LEADING TO", 6),
            (11, "ON", 5),
            (12, "ON", 5),
            (13, "ON", 5),
            (15, "ON", 13),
            (20, "ON", 12),
            (22, "ABOVE", 5),
            (22, "INSIDE", 4),
            (22, "WITH", 25),
            (24, "ON", 13),
            (24, "INSIDE", 4),
        ],
    );
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <livingroom floor>(5)",
            "[movetowards] <dining table>(13)",
            "[movetowards] <bedroom>(0)",
            "[movetowards] <childroom>(2)",
            "[movetowards] <kitchen>(6)",
        ],
    );
    s.expect_view(DOG, &[0, 1, 2, 4, 6, 8, 23, 27, 33, 39, 49, 50]);
    // Landing on the LOW_HEIGHT floor brings the basket down within the dog's reach.
    s.act(QUAD, "[land_on] <livingroom floor>(5)");
    s.expect_high(&[25], false);
    s.expect_state_of(&BASKET_DOWN_IN_THE_LIVINGROOM_6);
}

#[test]
fn the_dog_carries_the_orange_through_the_door_into_the_landed_basket() {
    let mut s = BASKET_DOWN_IN_THE_LIVINGROOM_6.clone();
    s.act(DOG, "[movetowards] <orange>(49)");
    s.expect_actions(
        DOG,
        &[
            "[grab] <orange>(49)",
            "[movetowards] <door>(8)",
            "[movetowards] <bed>(27)",
            "[movetowards] <livingroom>(4)",
        ],
    );
    s.act(DOG, "[grab] <orange>(49)");
    s.act(DOG, "[movetowards] <livingroom>(4)");
    s.expect_view(
        DOG,
        &[
            0, 2, 4, 5, 6, 8, 9, 10, 11, 12, 13, 15, 20, 22, 23, 24, 25, 49,
        ],
    );
    s.expect_seen_edges(
        DOG,
        &[
            (23, "HOLD", 49),
            (23, "ON", 5),
            (22, "ON", 5),
            (25, "ON", 5),
        ],
    );
    s.expect_unseen_edges(DOG, &[(23, "ON", 1), (49, "ON", 1)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_6,
            &["[movetowards] <basket>(25)", "[movetowards] <bedroom>(0)"],
            &[],
        ),
    );
    s.act(DOG, "[movetowards] <basket>(25)");
    s.expect_actions(
        DOG,
        &with(
            DOG_LIVINGROOM_6,
            &[
                "[putinto] <orange>(49) into <basket>(25)",
                "[movetowards] <bedroom>(0)",
            ],
            &[],
        ),
    );
    s.act(DOG, "[putinto] <orange>(49) into <basket>(25)");
    s.expect_seen_edges(QUAD, &[(49, "INSIDE", 25)]);
    s.expect_high(&[49], false);
}

#[test]
fn each_refusal_at_the_start_of_task16_gives_its_own_reason() {
    let mut s = TASK16.clone();
    // The knife is on the coffee table, but the dog has not moved next to it.
    s.refused(DOG, "[grab] <knife>(54)", Reason::NotClose);
    s.refused(DOG, "[open] <door>(8)", Reason::NotClose);
    s.refused(DOG, "[movetowards] <dining table>(13)", Reason::TooHigh);
    s.refused(DOG, "[movetowards] <plate>(51)", Reason::TooHigh);
    s.refused(DOG, "[movetowards] <bedroom>(0)", Reason::DoorClosed);
    s.refused(
        DOG,
        "[land_on] <livingroom floor>(5)",
        Reason::WrongRobotType,
    );
    s.refused(ARM, "[open] <door>(8)", Reason::NotOpenable);
    s.refused(ARM, "[grab] <knife>(54)", Reason::OutOfReach);
    s.refused(QUAD, "[land_on] <livingroom floor>(5)", Reason::NotFlying);
}

#[test]
fn a_flying_quadrotor_is_refused_unlandable_places_closed_doors_and_a_second_take_off() {
    let mut s = QUAD_FLYING.clone();
    s.refused(QUAD, "[land_on] <coffee table>(12)", Reason::NotLandable);
    s.refused(QUAD, "[movetowards] <sofa>(11)", Reason::NotLandable);
    s.refused(QUAD, "[land_on] <dining table>(13)", Reason::NotAbove);
    s.refused(QUAD, "[movetowards] <bedroom>(0)", Reason::DoorClosed);
    s.refused(
        QUAD,
        "[takeoff_from] <livingroom floor>(5)",
        Reason::NotLanded,
    );
}
