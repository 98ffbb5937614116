"""The style LangGap's self-contained HTML pages share (the report, the audit page): the page, its headings, its
tables and their filter boxes; each page adds its own rules after these."""

PAGE_STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.15em; margin-top: 2em; }
table { border-collapse: collapse; margin: .5em 0; }
th, td { border: 1px solid #ccc; padding: .25em .5em; text-align: left; }
input.filter { margin: .25em 0; padding: .2em .4em; width: 20em; }
.note { color: #555; font-size: .9em; }
"""
