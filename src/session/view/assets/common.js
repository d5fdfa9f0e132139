'use strict';
// What every page of `coherent view` shares. The page's data is JSON in the element
// #data; every string of it goes into the page as text (textContent, attribute values),
// never as markup.

const SVG_NS = 'http://www.w3.org/2000/svg';

function readData() {
  return JSON.parse(document.getElementById('data').textContent);
}

// An HTML element: attributes from `attrs` (`class` as the class name), then the
// children, strings as text nodes.
function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  setAttributes(e, attrs);
  append(e, children);
  return e;
}

// An SVG element, the same way.
function svgEl(tag, attrs, ...children) {
  const e = document.createElementNS(SVG_NS, tag);
  setAttributes(e, attrs);
  append(e, children);
  return e;
}

function setAttributes(e, attrs) {
  for (const [name, value] of Object.entries(attrs || {})) {
    if (value === null || value === undefined || value === false) continue;
    if (name === 'class') e.setAttribute('class', String(value));
    else e.setAttribute(name, value === true ? '' : String(value));
  }
}

function append(e, children) {
  for (const c of children.flat()) {
    if (c === null || c === undefined || c === false) continue;
    e.append(typeof c === 'string' || typeof c === 'number' ? document.createTextNode(String(c)) : c);
  }
}

// A definition list of [term, value] pairs; a value may be an element.
function facts(pairs, cls) {
  const dl = el('dl', { class: 'facts' + (cls ? ' ' + cls : '') });
  for (const [term, value, field] of pairs) {
    if (value === null || value === undefined || value === '') continue;
    dl.append(el('dt', {}, term), el('dd', { 'data-field': field || null }, value));
  }
  return dl;
}

function badge(text, cls) {
  return el('span', { class: 'badge ' + (cls || text) }, text);
}

// Folded text: a summary, then the text as written.
function folded(summary, text, open) {
  return el('details', { open: !!open }, el('summary', {}, summary), el('pre', {}, text));
}

function number(x, digits) {
  return x === null || x === undefined || Number.isNaN(x) ? '-' : Number(x).toFixed(digits);
}

function usd(x) {
  if (x === null || x === undefined) return '-';
  return '$' + (x !== 0 && Math.abs(x) < 0.01 ? x.toPrecision(3) : x.toFixed(4));
}

function thousands(n) {
  return String(n).replace(/\B(?=(\d{3})+(?!\d))/g, ',');
}

// Whether a key press belongs to a text field or comes with a modifier.
function notForUs(event) {
  const t = event.target;
  return event.altKey || event.ctrlKey || event.metaKey ||
    (t && (t.tagName === 'INPUT' || t.tagName === 'TEXTAREA' || t.isContentEditable));
}

// The page has drawn itself whole: marked for the tests and for timing.
function drawn() {
  performance.mark('coherent-drawn');
  document.body.dataset.drawn = 'yes';
}
