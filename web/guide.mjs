// Renders the user guide (docs/guide/*.md) to static HTML beside the page, so that web/dist is
// the project's site: web/dist/guide/index.html (docs/guide/README.md) and one page per file.
// Called by build.sh: node web/guide.mjs DOCS_GUIDE_DIR OUT_DIR. Markdown by `marked` (pinned in
// package-lock.json); nothing is fetched at run time (no scripts, styles inline).
//
// Links: `x.md` within the guide becomes `x.html` (`README.md` -> `index.html`), anchors kept;
// a link to any other file of the repository becomes its address in the repository named by
// Cargo.toml's `repository` (the one URL the README states), so no link on the site is dead.
import { readFileSync, writeFileSync, readdirSync, mkdirSync } from 'node:fs';
import { join, resolve, relative, dirname, basename } from 'node:path';
import { Marked } from 'marked';

const [guideArg, outArg] = process.argv.slice(2);
if (!guideArg || !outArg) {
  console.error('usage: node guide.mjs DOCS_GUIDE_DIR OUT_DIR');
  process.exit(2);
}
const guide = resolve(guideArg);
const out = resolve(outArg);
const root = resolve(guide, '../..');
const cargo = readFileSync(join(root, 'Cargo.toml'), 'utf8');
const repository = (cargo.match(/^repository = "([^"]+)"/m) || [])[1];
if (!repository) {
  console.error('guide.mjs: no `repository = "..."` in Cargo.toml');
  process.exit(2);
}

const pageName = (md) => (md === 'README.md' ? 'index.html' : md.replace(/\.md$/, '.html'));

/** The site's address of a link written in docs/guide/FILE. */
function link(href) {
  if (/^[a-z]+:/i.test(href) || href.startsWith('#')) return href;
  const [path, anchor] = href.split('#');
  const target = resolve(guide, path);
  const hash = anchor === undefined ? '' : `#${anchor}`;
  if (dirname(target) === guide && target.endsWith('.md')) return pageName(basename(target)) + hash;
  return `${repository}/blob/main/${relative(root, target)}${hash}`;
}

const marked = new Marked({ gfm: true });
marked.use({
  walkTokens(token) {
    if (token.type === 'link') token.href = link(token.href);
  },
  renderer: {
    // Headings carry GitHub's anchors (lowercase, spaces to '-', punctuation dropped), so that
    // `page.md#a-heading` links work on the site as on GitHub.
    heading({ tokens, depth }) {
      const text = this.parser.parseInline(tokens);
      const plain = tokens.map((t) => t.raw).join('');
      const id = plain.toLowerCase().trim().replace(/[^\p{L}\p{N}\s_-]/gu, '').replace(/\s/g, '-');
      return `<h${depth} id="${id}">${text}</h${depth}>\n`;
    },
  },
});

const style = `body{font:16px/1.5 system-ui,sans-serif;max-width:60rem;margin:2rem auto;padding:0 1rem;color:#1d232a}
pre{background:#f4f6f8;padding:.75rem;overflow-x:auto;font-size:13px;line-height:1.35}
code{font-family:ui-monospace,SFMono-Regular,Menlo,monospace;font-size:.9em}
table{border-collapse:collapse}td,th{border:1px solid #d0d7de;padding:.25rem .5rem;vertical-align:top}
nav{font-size:.9em;margin-bottom:1rem}a{color:#0b62c4}`;

mkdirSync(out, { recursive: true });
const pages = readdirSync(guide).filter((f) => f.endsWith('.md')).sort();
for (const md of pages) {
  const text = readFileSync(join(guide, md), 'utf8');
  const title = (text.match(/^# (.*)$/m) || [null, md])[1].replace(/`/g, '');
  const body = marked.parse(text);
  const html = `<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta http-equiv="Content-Security-Policy" content="default-src 'self'; style-src 'unsafe-inline'; img-src 'self' data:">
<title>${title.replace(/</g, '&lt;')} · urdf-dh guide</title>
<style>${style}</style>
</head>
<body>
<nav><a href="../index.html">the page</a> · <a href="index.html">the guide</a></nav>
${body}</body>
</html>
`;
  writeFileSync(join(out, pageName(md)), html);
}
console.error(`guide.mjs: ${pages.length} pages -> ${relative(process.cwd(), out) || out}`);
