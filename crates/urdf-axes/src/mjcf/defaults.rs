//! `<default>` classes: nested classes inherit their parent's attributes, an element takes
//! its `class` or else the innermost `childclass` of the bodies and frames around it, else
//! the top class `main` (MuJoCo's rules, "Default settings" in the MJCF reference).

use std::collections::HashMap;

use super::error::MjcfError;
use super::xml::Node;

/// The name of the top-level default class when it has none.
pub(crate) const MAIN: &str = "main";

/// One class: its parent and, per element tag, the attributes it sets.
#[derive(Debug, Default)]
struct Class {
    parent: Option<String>,
    elements: HashMap<String, Vec<(String, String)>>,
}

/// Every default class of a document.
#[derive(Debug, Default)]
pub(crate) struct Classes {
    classes: HashMap<String, Class>,
}

impl Classes {
    /// Reads every `<default>` element directly under `<mujoco>` (and the classes nested in
    /// them).
    ///
    /// # Errors
    /// A class defined twice; a nested `<default>` without a `class`.
    pub fn read(root: &Node) -> Result<Classes, MjcfError> {
        let mut out = Classes::default();
        out.classes.insert(MAIN.to_owned(), Class::default());
        for d in root.children.iter().filter(|c| c.name == "default") {
            out.add(d, None)?;
        }
        Ok(out)
    }

    fn add(&mut self, d: &Node, parent: Option<&str>) -> Result<(), MjcfError> {
        let name = match (d.attr("class"), parent) {
            (Some(c), _) => c.to_owned(),
            (None, None) => MAIN.to_owned(),
            (None, Some(_)) => {
                return Err(d.error("expected attribute 'class' on a nested <default>, found none"))
            }
        };
        let is_main_again = name == MAIN && parent.is_none();
        if !is_main_again && self.classes.contains_key(&name) {
            return Err(d.error(format!(
                "expected unique default class names, found '{name}' defined again"
            )));
        }
        let parent = if name == MAIN {
            None
        } else {
            Some(parent.unwrap_or(MAIN).to_owned())
        };
        let class = self.classes.entry(name.clone()).or_default();
        class.parent = parent;
        for e in d.children.iter().filter(|c| c.name != "default") {
            let attrs = class.elements.entry(e.name.clone()).or_default();
            for (k, v) in &e.attrs {
                attrs.retain(|(old, _)| old != k);
                attrs.push((k.clone(), v.clone()));
            }
        }
        for nested in d.children.iter().filter(|c| c.name == "default") {
            self.add(nested, Some(&name))?;
        }
        Ok(())
    }

    /// Whether class `name` is defined.
    pub fn has(&self, name: &str) -> bool {
        self.classes.contains_key(name)
    }

    /// The class that applies to element `e` when the innermost enclosing `childclass` is
    /// `childclass`: its own `class`, else `childclass`, else `main`.
    ///
    /// # Errors
    /// A `class` that is not defined.
    pub fn class_of<'a>(
        &self,
        e: &'a Node,
        childclass: Option<&'a str>,
    ) -> Result<&'a str, MjcfError> {
        match e.attr("class") {
            Some(c) if self.has(c) => Ok(c),
            Some(c) => Err(e.error(format!(
                "attribute 'class': expected a default class, found '{c}', which no <default> defines"
            ))),
            None => Ok(childclass.unwrap_or(MAIN)),
        }
    }

    /// The value of attribute `attr` of element `e`: its own, else the nearest class's from
    /// `class` up to `main` for elements `tag` (`joint`; `equality` for every kind of equality
    /// constraint).
    pub fn attr<'a>(&'a self, e: &'a Node, tag: &str, class: &str, attr: &str) -> Option<&'a str> {
        if let Some(v) = e.attr(attr) {
            return Some(v);
        }
        let mut name = Some(class);
        // Classes form a tree (each defined once, parents defined first): the bound guards only
        // against a broken invariant.
        for _ in 0..=self.classes.len() {
            let class = self.classes.get(name?)?;
            if let Some(v) = class
                .elements
                .get(tag)
                .and_then(|a| a.iter().find(|(k, _)| k == attr))
            {
                return Some(v.1.as_str());
            }
            name = class.parent.as_deref();
        }
        None
    }
}
