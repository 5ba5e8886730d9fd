//! A CAD model's class from its name, for the importers: catalogue entries and model files name
//! what they are ("Bedside table", "short_fridge") but not in the project's classes.

/// Names (lowercase word sequences) that would match a class by one of their words but are
/// something else: a bookcase is a shelf, a bedside table a cabinet, a cup cake no cup.
const NOT_THEIR_WORDS: [(&str, Option<&str>); 18] = [
    ("island bath", None),
    ("intercom", None),
    ("remote control", None),
    ("japanese style screen", None),
    ("bedside table", Some("cabinet")),
    ("television cabinet", Some("cabinet")),
    ("tv unit", Some("cabinet")),
    ("tv stand", Some("cabinet")),
    ("dressing table", Some("table")),
    ("desk lamp", None),
    ("table fan", None),
    ("table tennis", None),
    ("cup cake", None),
    ("bread box", None),
    ("letters box", None),
    ("plant box", None),
    ("flower box", None),
    ("chest freezer", None),
];

/// A class for each word that names it, in order of precedence: "microwave" before "oven",
/// "sofa bed" is a bed, "wine bottle" a bottle.
const CLASS_WORDS: [(&str, &[&str]); 17] = [
    ("microwave", &["microwave"]),
    ("fridge", &["fridge", "refrigerator", "freezer"]),
    ("dishwasher", &["dishwasher"]),
    ("oven", &["oven", "cooker"]),
    ("bed", &["bed", "crib", "futon"]),
    ("sofa", &["sofa", "couch"]),
    ("chair", &["chair", "armchair", "stool"]),
    ("shelf", &["bookcase", "shelves", "shelf"]),
    (
        "cabinet",
        &[
            "cabinet", "cupboard", "dresser", "wardrobe", "chest", "drawers",
        ],
    ),
    ("table", &["table", "desk"]),
    ("monitor", &["tv", "monitor", "screen", "imac"]),
    ("bottle", &["bottle"]),
    ("cup", &["cup", "mug"]),
    ("bowl", &["bowl"]),
    ("book", &["book"]),
    ("box", &["box", "crate"]),
    ("counter", &["island"]),
];

/// The project class that `name` names (any separators between words), `None` when it names
/// none of them.
pub fn class_of_name(name: &str) -> Option<&'static str> {
    let words: Vec<String> = name
        .to_lowercase()
        .split(|c: char| !c.is_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(str::to_owned)
        .collect();
    let phrase = words.join(" ");
    for (exception, class) in NOT_THEIR_WORDS {
        if contains_phrase(&phrase, exception) {
            return class;
        }
    }
    CLASS_WORDS
        .iter()
        .find(|(_, names)| names.iter().any(|n| words.iter().any(|w| w == n)))
        .map(|(class, _)| *class)
}

/// Whether the word sequence `phrase` holds the word sequence `part`.
fn contains_phrase(phrase: &str, part: &str) -> bool {
    format!(" {phrase} ").contains(&format!(" {part} "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_name_classes() {
        assert_eq!(class_of_name("short_fridge"), Some("fridge"));
        assert_eq!(class_of_name("wooden_cabinet"), Some("cabinet"));
        assert_eq!(class_of_name("microwave"), Some("microwave"));
        assert_eq!(class_of_name("flat_stove"), None);
        assert_eq!(class_of_name("basin_faucet"), None);
        assert_eq!(class_of_name("Bedside table"), Some("cabinet"));
    }
}
