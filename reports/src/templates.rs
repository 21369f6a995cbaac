//! The report's pages rendered from templates (MiniJinja): `reports/templates/*.html`,
//! compiled into the crate with `include_str!`, each given a plain `serde::Serialize` model
//! of its page (`index::IndexPage`, `run_pages::RunPage`, the modules above this one).
//!
//! HTML is escaped automatically (the templates are `.html`: `&`, `<`, `>`, `"` and `'`, so
//! that paths such as `plots/x.png` stay as they are); the only text inserted as it is
//! is the pages' own style sheet and script (`reports/assets/`), given to every page as the
//! globals `style` and `script`. A name a template uses that its model lacks is an error, not
//! an empty string, so a page cannot silently lose a field.

use minijinja::value::{Serde, Value};
use minijinja::{AutoEscape, Environment, UndefinedBehavior};
use serde::Serialize;

/// The templates, by name.
const TEMPLATES: [(&str, &str); 4] = [
    ("head.html", include_str!("../templates/head.html")),
    ("macros.html", include_str!("../templates/macros.html")),
    ("index.html", include_str!("../templates/index.html")),
    ("run.html", include_str!("../templates/run.html")),
];

/// A template that does not parse, or a page that does not render.
#[derive(Debug, thiserror::Error)]
#[error("template {template}: {message}")]
pub struct TemplateError {
    /// The template.
    pub template: String,
    /// What went wrong, with the line.
    pub message: String,
}

/// The error's message with every cause (an included template's error names its line).
fn message(e: &minijinja::Error) -> String {
    let mut text = e.to_string();
    let mut source = std::error::Error::source(e);
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// `text` escaped for HTML text and attribute values.
pub fn escape_html(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The templates, ready to render pages.
pub struct Pages {
    env: Environment<'static>,
}

impl Pages {
    /// Parses every template.
    pub fn new() -> Result<Self, TemplateError> {
        Self::with(&TEMPLATES)
    }

    /// Parses `templates` (name and source each) in the pages' settings.
    fn with(templates: &[(&'static str, &'static str)]) -> Result<Self, TemplateError> {
        let mut env = Environment::new();
        env.set_undefined_behavior(UndefinedBehavior::Strict);
        env.set_syntax(
            minijinja::syntax::SyntaxConfig::builder()
                .trim_blocks(true)
                .lstrip_blocks(true)
                .build()
                .map_err(|e| TemplateError { template: "syntax".into(), message: message(&e) })?,
        );
        // Strings are escaped by `escape_html`; everything else (numbers, safe strings, the
        // strict check of undefined names) as MiniJinja does.
        env.set_formatter(|out, state, value| match (state.auto_escape(), value.as_str()) {
            (AutoEscape::Html, Some(text)) if !value.is_safe() => {
                Ok(out.write_str(&escape_html(text))?)
            }
            _ => minijinja::escape_formatter(out, state, value),
        });
        env.add_global("style", Value::from_safe_string(crate::html::STYLE.to_owned()));
        env.add_global("script", Value::from_safe_string(crate::html::SCRIPT.to_owned()));
        for &(name, source) in templates {
            env.add_template(name, source)
                .map_err(|e| TemplateError { template: name.into(), message: message(&e) })?;
        }
        Ok(Self { env })
    }

    /// Renders template `name` with `model`.
    pub fn render(&self, name: &str, model: &impl Serialize) -> Result<String, TemplateError> {
        let fail =
            |e: minijinja::Error| TemplateError { template: name.into(), message: message(&e) };
        self.env.get_template(name).map_err(fail)?.render(Value::from(Serde(model))).map_err(fail)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Model {
        title: String,
        href: String,
    }

    #[test]
    fn every_template_parses_and_html_is_escaped() {
        let pages = Pages::new().expect("the templates parse");
        let mut pages_env =
            Pages::with(&[("t.html", "<a href=\"{{ href }}\">{{ title }}</a>")]).expect("parses");
        let model = Model { title: "<b>&'\"</b>".into(), href: "plots/a b.png".into() };
        let text = pages_env.render("t.html", &model).expect("renders");
        assert_eq!(text, "<a href=\"plots/a b.png\">&lt;b&gt;&amp;&#39;&quot;&lt;/b&gt;</a>");
        // The style and the script go in as they are.
        pages_env = Pages::with(&[("s.html", "{{ style }}")]).expect("parses");
        assert_eq!(pages_env.render("s.html", &model).expect("renders"), crate::html::STYLE);
        // A field the model lacks is an error.
        let e = pages.render("run.html", &model).expect_err("strict");
        assert!(e.to_string().contains("run.html"), "{e}");
    }
}
