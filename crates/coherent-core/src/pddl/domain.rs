//! The PDDL domain of one rule set: the rules of docs/semantics.md as action schemas
//! (docs/pddl.md explains each predicate and schema against that page).
//!
//! One schema per robot type and verb (a `movetowards` to a room and one to a thing are
//! two), so that every action of the rules is exactly one PDDL action and a plan's length
//! is its step count. What the rules derive from the state at each step (what a robot
//! sees, what a fixed arm reaches) is either kept as a fluent that every action keeps
//! up to date (`inroom`, `hidden`, `anc`) or named by the action itself (the chain of
//! at most four things between what a fixed arm acts on and its surface).

use crate::task::RuleSet;

/// The domain's name for a rule set.
pub fn domain_name(rules: RuleSet) -> &'static str {
    match rules {
        RuleSet::Compatible => "coherent-compatible",
        RuleSet::Geometric => "coherent-geometric",
    }
}

/// The rule set's name as task files write it.
pub(crate) fn rules_name(rules: RuleSet) -> &'static str {
    match rules {
        RuleSet::Compatible => "compatible",
        RuleSet::Geometric => "geometric",
    }
}

/// The domain of `rules`, with a header naming the program's version.
pub fn domain(rules: RuleSet) -> String {
    let mut d = format!(
        ";; The COHERENT benchmark's rules (docs/semantics.md), {} rule set, written by coherent {}.\n\
         ;; docs/pddl.md explains every predicate and schema. Typed STRIPS with negative\n\
         ;; preconditions, existential and disjunctive preconditions and conditional effects;\n\
         ;; one action per step of the rules, all of cost 1.\n",
        rules_name(rules),
        env!("CARGO_PKG_VERSION")
    );
    d.push_str(&format!("(define (domain {})\n", domain_name(rules)));
    d.push_str(HEAD);
    for schema in [
        dog_hands(),
        dog_puts(),
        dog_moves(),
        quadrotor_land_takeoff(),
        quadrotor_moves(),
        arm_hands(),
        arm_puts(rules),
    ] {
        d.push_str(&schema);
    }
    d.push_str(")\n");
    d
}

const HEAD: &str =
    "  (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions
    :existential-preconditions :conditional-effects :equality)
  (:types
    room robot thing - object
    quadrotor dog arm - robot
    fixed movable - thing
    carrier - movable)
  (:predicates
    ;; what never changes
    (grabable ?x - thing) (surface ?x - thing) (container ?x - thing) (holder ?x - thing)
    (landable ?x - thing) (high-height ?x - thing) (low-height ?x - thing)
    (floor ?x - object) (door ?x - thing) (is-carrier ?x - thing)
    (leads ?d - thing ?r - room) (floor-of ?f - thing ?r - room)
    (basket-of ?q - quadrotor ?b - thing) (arm-base ?a - arm ?s - thing)
    ;; the edges
    (on ?x - object ?y - object) (inside ?x - object ?y - object) (at ?x - thing ?y - object)
    (close ?d - dog ?x - object) (holds ?r - robot ?x - movable) (above ?q - quadrotor ?x - thing)
    ;; the states and the ON_HIGH_SURFACE mark
    (is-open ?x - thing) (is-closed ?x - thing) (opened ?x - thing)
    (flying ?q - quadrotor) (landed ?q - quadrotor) (marked ?x - thing) (free ?r - robot)
    ;; derived from the edges and states, kept up to date by every action
    (hidden ?x - thing) (inroom ?x - thing ?r - room) (anc ?x - thing ?h - thing))
";

/// `?x` seen by a robot in room `?r`: in the room's closure and not hidden, or the basket
/// of a quadrotor in the room, or directly in that basket (docs/semantics.md,
/// "Observations").
fn seen(x: &str, r: &str) -> String {
    format!(
        "(or (and (inroom {x} {r}) (not (hidden {x})))
              (exists (?sq - quadrotor) (and (inside ?sq {r}) (basket-of ?sq {x})))
              (exists (?sq - quadrotor ?sb - carrier)
                (and (inside ?sq {r}) (basket-of ?sq ?sb) (inside {x} ?sb))))"
    )
}

/// `?me` is in a room from which it sees `x`.
fn sees(me: &str, x: &str) -> String {
    format!(
        "(exists (?here - room) (and (inside {me} ?here)\n            {}))",
        seen(x, "?here")
    )
}

/// What the dog's `open` and `close` and the arm's do to the node and what is in it.
fn open_effect(x: &str) -> String {
    format!(
        "(is-open {x}) (opened {x}) (not (is-closed {x}))
      (forall (?y - thing) (when (inside ?y {x}) (not (hidden ?y))))"
    )
}

fn close_effect(x: &str) -> String {
    format!(
        "(is-closed {x}) (not (is-open {x})) (not (opened {x}))
      (forall (?y - thing) (when (inside ?y {x}) (hidden ?y)))"
    )
}

/// A grab: `x` loses its location (its only one), and it and everything on or in it,
/// at any depth, leave the rooms they were seen from.
fn lift(x: &str) -> String {
    format!(
        "(forall (?p - object) (when (on {x} ?p) (and (not (on {x} ?p)) (not (at {x} ?p)))))
      (forall (?p - object) (when (inside {x} ?p) (and (not (inside {x} ?p)) (not (at {x} ?p)))))
      (not (hidden {x}))
      (forall (?r - room) (when (inroom {x} ?r) (not (inroom {x} ?r))))
      (forall (?y - movable ?r - room) (when (and (anc ?y {x}) (inroom ?y ?r)) (not (inroom ?y ?r))))
      (forall (?k - carrier) (when (anc {x} ?k) (not (anc {x} ?k))))
      (forall (?y - movable ?k - carrier) (when (and (anc ?y {x}) (anc {x} ?k)) (not (anc ?y ?k))))"
    )
}

/// A put of `h` on or into `t` (`rel`: `on` or `inside`): the new edge, and `h` with
/// what is on or in it joins the rooms `t` is seen from and the carriers above `t`.
fn place(h: &str, rel: &str, t: &str) -> String {
    format!(
        "({rel} {h} {t}) (at {h} {t})
      (forall (?r - room) (when (inroom {t} ?r) (inroom {h} ?r)))
      (forall (?y - movable ?r - room) (when (and (anc ?y {h}) (inroom {t} ?r)) (inroom ?y ?r)))
      (when (is-carrier {t}) (anc {h} {t}))
      (forall (?k - carrier) (when (anc {t} ?k) (anc {h} ?k)))
      (forall (?y - movable) (when (and (anc ?y {h}) (is-carrier {t})) (anc ?y {t})))
      (forall (?y - movable ?k - carrier) (when (and (anc ?y {h}) (anc {t} ?k)) (anc ?y ?k)))"
    )
}

fn dog_hands() -> String {
    format!(
        "
  ;; robot dog: docs/semantics.md, \"Robot dog\"
  (:action dog-open
    :parameters (?d - dog ?x - thing)
    :precondition (and (free ?d) (close ?d ?x) (or (container ?x) (door ?x)) (is-closed ?x)
      {seen_x})
    :effect (and {open}))
  (:action dog-close
    :parameters (?d - dog ?x - thing)
    :precondition (and (free ?d) (close ?d ?x) (or (container ?x) (door ?x)) (is-open ?x)
      {seen_x})
    :effect (and {close}))
  (:action dog-grab
    :parameters (?d - dog ?x - movable)
    :precondition (and (free ?d) (close ?d ?x) (grabable ?x)
      {seen_x})
    :effect (and (not (free ?d)) (holds ?d ?x) (not (close ?d ?x))
      {lift}))
",
        seen_x = sees("?d", "?x"),
        open = open_effect("?x"),
        close = close_effect("?x"),
        lift = lift("?x"),
    )
}

fn dog_puts() -> String {
    let put = |verb: &str, rel: &str, kind: &str| {
        let extra = if rel == "inside" { " (opened ?t)" } else { "" };
        format!(
            "  (:action dog-{verb}
    :parameters (?d - dog ?h - movable ?t - thing)
    :precondition (and (holds ?d ?h) (close ?d ?t) ({kind} ?t){extra}
      {seen_t})
    :effect (and (not (holds ?d ?h)) (free ?d) (close ?d ?h)
      {place}))
",
            seen_t = sees("?d", "?t"),
            place = place("?h", rel, "?t"),
        )
    };
    put("putinto", "inside", "container") + &put("puton", "on", "surface")
}

fn dog_moves() -> String {
    format!(
        "  (:action dog-movetowards
    :parameters (?d - dog ?x - thing)
    :precondition (and (not (close ?d ?x)) (not (floor ?x)) (not (high-height ?x)) (not (marked ?x))
      {seen_x})
    :effect (and
      (forall (?y - object) (when (close ?d ?y) (not (close ?d ?y))))
      (close ?d ?x)
      (forall (?y - object) (when (and (inside ?y ?x) (container ?x) (opened ?x)) (close ?d ?y)))
      (forall (?p - object) (when (and (at ?x ?p) (not (floor ?p))) (close ?d ?p)))
      (forall (?y - object) (when (and (on ?y ?x) (surface ?x) (not (floor ?x))) (close ?d ?y)))))
  (:action dog-movetowards-room
    :parameters (?d - dog ?to - room)
    :precondition {next}
    :effect (and
      (forall (?y - object) (when (close ?d ?y) (not (close ?d ?y))))
      (forall (?p - object) (when (on ?d ?p) (not (on ?d ?p))))
      (forall (?f - thing) (when (floor-of ?f ?to) (on ?d ?f)))
      (forall (?r - room) (when (inside ?d ?r) (not (inside ?d ?r))))
      (inside ?d ?to)))
",
        seen_x = sees("?d", "?x"),
        next = next_room("?d", "?to"),
    )
}

/// `to` is a room next to the robot's, through a door that is open (docs/semantics.md,
/// "next rooms"); the door is seen as it leads to the robot's room.
fn next_room(me: &str, to: &str) -> String {
    format!(
        "(exists (?here - room ?door - thing)
      (and (inside {me} ?here) (leads ?door ?here) (leads ?door {to}) (not (= ?here {to}))
           (opened ?door)))"
    )
}

fn quadrotor_land_takeoff() -> String {
    format!(
        "
  ;; quadrotor: docs/semantics.md, \"Quadrotor\"
  (:action quadrotor-land_on
    :parameters (?q - quadrotor ?s - thing)
    :precondition (and (flying ?q) (above ?q ?s) (landable ?s)
      {seen_s})
    :effect (and (landed ?q) (not (flying ?q)) (not (above ?q ?s)) (on ?q ?s)
      (forall (?b - carrier) (when (basket-of ?q ?b) (and (on ?b ?s) (at ?b ?s))))
      (forall (?b - carrier ?r - room) (when (and (basket-of ?q ?b) (inroom ?s ?r)) (inroom ?b ?r)))
      (forall (?b - carrier ?y - movable ?r - room)
        (when (and (basket-of ?q ?b) (anc ?y ?b) (inroom ?s ?r)) (inroom ?y ?r)))
      (forall (?b - carrier) (when (and (basket-of ?q ?b) (high-height ?s)) (marked ?b)))
      (forall (?b - carrier ?y - thing)
        (when (and (basket-of ?q ?b) (high-height ?s) (inside ?y ?b)) (marked ?y)))
      (forall (?b - carrier)
        (when (and (basket-of ?q ?b) (not (high-height ?s)) (low-height ?s) (marked ?b))
          (not (marked ?b))))
      (forall (?b - carrier ?y - thing)
        (when (and (basket-of ?q ?b) (not (high-height ?s)) (low-height ?s) (marked ?b) (inside ?y ?b))
          (not (marked ?y))))))
  (:action quadrotor-takeoff_from
    :parameters (?q - quadrotor ?s - thing)
    :precondition (and (landed ?q) (on ?q ?s)
      {seen_s})
    :effect (and (flying ?q) (not (landed ?q)) (not (on ?q ?s)) (above ?q ?s)
      (forall (?b - carrier) (when (basket-of ?q ?b) (and (not (on ?b ?s)) (not (at ?b ?s)) (marked ?b))))
      (forall (?b - carrier ?y - thing) (when (and (basket-of ?q ?b) (inside ?y ?b)) (marked ?y)))
      (forall (?b - carrier ?z - dog) (when (basket-of ?q ?b) (not (close ?z ?b))))
      (forall (?b - carrier ?z - dog ?y - thing)
        (when (and (basket-of ?q ?b) (inside ?y ?b)) (not (close ?z ?y))))
      (forall (?b - carrier ?r - room) (when (and (basket-of ?q ?b) (inroom ?b ?r)) (not (inroom ?b ?r))))
      (forall (?b - carrier ?y - movable ?r - room)
        (when (and (basket-of ?q ?b) (anc ?y ?b) (inroom ?y ?r)) (not (inroom ?y ?r))))))
",
        seen_s = sees("?q", "?s"),
    )
}

fn quadrotor_moves() -> String {
    format!(
        "  (:action quadrotor-movetowards
    :parameters (?q - quadrotor ?s - thing)
    :precondition (and (flying ?q) (landable ?s)
      (exists (?here - room ?a - thing)
        (and (inside ?q ?here) (above ?q ?a) (landable ?a) (not (= ?a ?s))
             {seen_a}
             {seen_s})))
    :effect (and (forall (?a - thing) (when (above ?q ?a) (not (above ?q ?a)))) (above ?q ?s)))
  (:action quadrotor-movetowards-room
    :parameters (?q - quadrotor ?to - room)
    :precondition (and (flying ?q) {next})
    :effect (and
      (forall (?a - thing) (when (above ?q ?a) (not (above ?q ?a))))
      (forall (?f - thing) (when (floor-of ?f ?to) (above ?q ?f)))
      (forall (?r - room) (when (inside ?q ?r) (not (inside ?q ?r))))
      (inside ?q ?to)))
",
        seen_a = seen("?a", "?here"),
        seen_s = seen("?s", "?here"),
        next = next_room("?q", "?to"),
    )
}

/// The chain of `via` things between `x` and arm `a`'s surface (docs/semantics.md,
/// "Robot arm"): `x` on or in `?c1`, that on or in `?c2`..., the last standing `ON` the
/// surface, none of them hidden; five levels down only under a surface or container.
/// The chain is the action's parameters, so that checking a plan grounds no
/// quantifier over chains.
fn chain(a: &str, x: &str, via: usize) -> String {
    let links: Vec<String> = (1..=via).map(|i| format!("{x}{i}")).collect();
    let nodes: Vec<&str> = std::iter::once(x)
        .chain(links.iter().map(String::as_str))
        .collect();
    let mut parts = Vec::new();
    for (i, n) in nodes.iter().enumerate() {
        parts.push(format!("(not (hidden {n}))"));
        match nodes.get(i + 1) {
            Some(next) => parts.push(format!("(at {n} {next})")),
            None => parts.push(format!(
                "(exists (?base - thing) (and (arm-base {a} ?base) (on {n} ?base)))"
            )),
        }
    }
    if via == 4 {
        parts.push(format!("(holder {})", nodes[1]));
    }
    parts.join(" ")
}

/// The parameters naming a chain of `via` things above `x`.
fn chain_params(x: &str, via: usize) -> String {
    (1..=via).map(|i| format!(" {x}{i} - thing")).collect()
}

/// The name of an arm schema whose chain has `via` things: `arm-grab`, `arm-grab-via2`.
pub(crate) fn arm_schema(verb: &str, via: usize) -> String {
    match via {
        0 => format!("arm-{verb}"),
        _ => format!("arm-{verb}-via{via}"),
    }
}

/// The most things between what an arm acts on and its surface.
pub(crate) const MAX_VIA: usize = 4;

fn arm_hands() -> String {
    let mut d = String::from("\n  ;; robot arm: docs/semantics.md, \"Robot arm\"\n");
    for via in 0..=MAX_VIA {
        d.push_str(&format!(
            "  (:action {open_name}
    :parameters (?a - arm ?x - thing{params})
    :precondition (and (free ?a) (container ?x) (is-closed ?x)
      {chain})
    :effect (and {open}))
  (:action {close_name}
    :parameters (?a - arm ?x - thing{params})
    :precondition (and (free ?a) (container ?x) (is-open ?x)
      {chain})
    :effect (and {close}))
  (:action {grab_name}
    :parameters (?a - arm ?x - movable{params})
    :precondition (and (free ?a) (grabable ?x)
      {chain})
    :effect (and (not (free ?a)) (holds ?a ?x)
      {lift}))
",
            open_name = arm_schema("open", via),
            close_name = arm_schema("close", via),
            grab_name = arm_schema("grab", via),
            params = chain_params("?x", via),
            chain = chain("?a", "?x", via),
            open = open_effect("?x"),
            close = close_effect("?x"),
            lift = lift("?x"),
        ));
    }
    d
}

/// The arm's puts; what they do to the `ON_HIGH_SURFACE` mark is the one difference
/// between the rule sets. A put on the arm's own surface needs no chain (and no
/// `SURFACES`).
fn arm_puts(rules: RuleSet) -> String {
    let mark = match rules {
        RuleSet::Compatible => "(marked ?h)".to_owned(),
        RuleSet::Geometric => "(when (or (high-height ?t) (marked ?t)) (marked ?h))
      (when (and (not (high-height ?t)) (not (marked ?t))) (not (marked ?h)))"
            .to_owned(),
    };
    let mut d = String::new();
    for via in 0..=MAX_VIA {
        let on_reached = format!("(and (surface ?t) {})", chain("?a", "?t", via));
        let on = if via == 0 {
            format!("(or (arm-base ?a ?t) {on_reached})")
        } else {
            on_reached
        };
        d.push_str(&format!(
            "  (:action {into_name}
    :parameters (?a - arm ?h - movable ?t - thing{params})
    :precondition (and (holds ?a ?h) (container ?t) (opened ?t)
      {chain})
    :effect (and (not (holds ?a ?h)) (free ?a) {mark}
      {into}))
  (:action {on_name}
    :parameters (?a - arm ?h - movable ?t - thing{params})
    :precondition (and (holds ?a ?h)
      {on})
    :effect (and (not (holds ?a ?h)) (free ?a) {mark}
      {on_place}))
",
            into_name = arm_schema("putinto", via),
            on_name = arm_schema("puton", via),
            params = chain_params("?t", via),
            chain = chain("?a", "?t", via),
            into = place("?h", "inside", "?t"),
            on_place = place("?h", "on", "?t"),
        ));
    }
    d
}
