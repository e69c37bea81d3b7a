//! Typed events: what a controller reports as having happened at one
//! instant (a dead-lock detected, a localizer warning, a supervisor
//! decision), as structured data rather than text.
//!
//! An event has a `kind` (a short name the controller documents), the time
//! it happened, optionally a position, and a payload of named values.
//! Serialised with serde it is one JSON object:
//!
//! ```
//! use robot::{Event, Vec2};
//!
//! let e = Event::new("deadlock", 12.5)
//!     .at(Vec2::new(2.0, 3.25))
//!     .with("events", 3.0)
//!     .with("trigger", "CP2");
//! assert_eq!(
//!     serde_json::to_string(&e).unwrap(),
//!     r#"{"kind":"deadlock","time_s":12.5,"position":{"x":2.0,"y":3.25},"payload":{"events":3.0,"trigger":"CP2"}}"#
//! );
//! assert_eq!(e.number("events"), Some(3.0));
//! assert_eq!(e.text("trigger"), Some("CP2"));
//! ```

use std::collections::BTreeMap;

use crate::Vec2;

/// One value of an event's payload.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum EventValue {
    /// A flag.
    Bool(bool),
    /// A number (finite: JSON has no NaN or infinities).
    Number(f64),
    /// A name or a short text.
    Text(String),
}

impl From<bool> for EventValue {
    fn from(v: bool) -> EventValue {
        EventValue::Bool(v)
    }
}

impl From<f64> for EventValue {
    fn from(v: f64) -> EventValue {
        EventValue::Number(v)
    }
}

impl From<&str> for EventValue {
    fn from(v: &str) -> EventValue {
        EventValue::Text(v.to_string())
    }
}

impl From<String> for EventValue {
    fn from(v: String) -> EventValue {
        EventValue::Text(v)
    }
}

/// Something that happened during a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Event {
    /// What happened: a short name documented by the controller that emits
    /// it (e.g. `CP2`, `deadlock`, `warning`, `decision`).
    pub kind: String,
    /// When, seconds since the start of the run.
    pub time_s: f64,
    /// Where, metres, in the frame the controller works in (its own pose
    /// estimate: odometry or localizer), if the event has a place.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<Vec2>,
    /// Named values, in name order.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub payload: BTreeMap<String, EventValue>,
}

impl Event {
    /// An event of `kind` at `time_s`, without position or payload.
    pub fn new(kind: impl Into<String>, time_s: f64) -> Event {
        Event {
            kind: kind.into(),
            time_s,
            position: None,
            payload: BTreeMap::new(),
        }
    }

    /// The same event, placed at `position`.
    pub fn at(mut self, position: Vec2) -> Event {
        self.position = Some(position);
        self
    }

    /// The same event with `key` set to `value` in its payload.
    pub fn with(mut self, key: impl Into<String>, value: impl Into<EventValue>) -> Event {
        self.payload.insert(key.into(), value.into());
        self
    }

    /// A number of the payload.
    pub fn number(&self, key: &str) -> Option<f64> {
        match self.payload.get(key) {
            Some(EventValue::Number(v)) => Some(*v),
            _ => None,
        }
    }

    /// A text of the payload.
    pub fn text(&self, key: &str) -> Option<&str> {
        match self.payload.get(key) {
            Some(EventValue::Text(v)) => Some(v),
            _ => None,
        }
    }

    /// A flag of the payload.
    pub fn flag(&self, key: &str) -> Option<bool> {
        match self.payload.get(key) {
            Some(EventValue::Bool(v)) => Some(*v),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn events_round_trip_through_json() {
        let e = Event::new("decision", 3.0)
            .with("choice", "automove")
            .with("f_auto", 0.0081)
            .with("rule", false);
        let back: Event = serde_json::from_str(&serde_json::to_string(&e).unwrap()).unwrap();
        assert_eq!(back, e);
        assert_eq!(back.flag("rule"), Some(false));
        assert_eq!(back.number("choice"), None);
        let bare: Event = serde_json::from_str(r#"{"kind":"CP1","time_s":0.0}"#).unwrap();
        assert_eq!(bare, Event::new("CP1", 0.0));
    }
}
